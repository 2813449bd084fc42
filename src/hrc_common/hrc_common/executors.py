"""The executor the hrc nodes spin on: :class:`LeanExecutor`, chosen by ``HRC_EXECUTOR``.

The lockstep graph makes one executor turn per message in each node, so the executor's own
Python work per turn bounds the graph's rate (rclpy's wait-set rebuild was 48-58% of the sim's
and the human node's busy samples, docs/engines.md "The nodes' executor").

``HRC_EXECUTOR=rclpy`` runs rclpy's own ``SingleThreadedExecutor`` instead: an escape hatch kept
while :class:`LeanExecutor` leans on rclpy's internals (``_rclpy.WaitSet``, the executor's
``_tasks``, ``_make_handler``, ``_take_*``, ``Subscription._callback_type``), so a lab whose
rclpy changed them can still run; the same callbacks in the same order, only slower.
"""

import os

from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor, TimeoutObject
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription
from rclpy.utilities import timeout_sec_to_nsec

# HRC_EXECUTOR: the executor run_node spins a node on. 'lean' (default): LeanExecutor;
# 'rclpy': rclpy's SingleThreadedExecutor (the escape hatch, see the module docstring).
EXECUTOR_VARIABLE = 'HRC_EXECUTOR'
EXECUTORS = ('lean', 'rclpy')


class LeanExecutor(SingleThreadedExecutor):
    """A single-threaded executor that does rclpy's work per turn with less Python.

    The same callbacks in the same order as rclpy's ``SingleThreadedExecutor`` (per node:
    waitables, timers, subscriptions, guard conditions, clients, services, each kind in creation
    order; every entity ready after one wait is served before the next wait), but:

    * the wait set is built once and refilled each turn (rclpy builds a new one, enters every
      handle's context and filters every entity at every turn); it is rebuilt only when a node's
      entities change (compared by identity each turn, a few microseconds);
    * subscriptions, timers and guard conditions are called directly, not through a ``Task``
      and a coroutine each; clients, services, waitables and tasks (futures' done callbacks) go
      through rclpy's own handlers, so futures and async callbacks behave as in rclpy.

    Handles are not entered (rclpy enters them so that another thread cannot destroy an entity
    during the wait): the hrc nodes create and destroy entities only in the executor's thread.
    """

    def __init__(self, *, context=None):
        super().__init__(context=context)
        self._node_order = []          # nodes in the order they were added
        self._entity_key = None        # identity of every entity the wait set was built for
        self._wait_set = None
        self._plan = ()                # per node: (node, waitables, timers, subs, guards, ...)
        self._executor_guards = ()

    def add_node(self, node) -> bool:
        """Add a node (served in the order nodes were added)."""
        added = super().add_node(node)
        if added:
            self._node_order.append(node)
        return added

    def remove_node(self, node) -> None:
        """Stop serving a node."""
        super().remove_node(node)
        if node in self._node_order:
            self._node_order.remove(node)

    def _current_key(self, nodes) -> tuple:
        return tuple((node, tuple(node.waitables), tuple(node.timers), tuple(node.subscriptions),
                      tuple(node.guards), tuple(node.clients), tuple(node.services))
                     for node in nodes) + ((self._guard, self._sigint_gc),)

    def _rebuild(self, key) -> None:
        """Size a wait set for ``key``'s entities and remember each one's handle pointer."""
        counts = [0, 2, 0, 0, 0, 0]  # subscriptions, guards (2: the executor's), timers, ...
        plan = []
        for node, waitables, timers, subscriptions, guards, clients, services in key[:-1]:
            counts[0] += len(subscriptions)
            counts[1] += len(guards)
            counts[2] += len(timers)
            counts[3] += len(clients)
            counts[4] += len(services)
            for waitable in waitables:
                entities = waitable.get_num_entities()
                counts[0] += entities.num_subscriptions
                counts[1] += entities.num_guard_conditions
                counts[2] += entities.num_timers
                counts[3] += entities.num_clients
                counts[4] += entities.num_services
                counts[5] += entities.num_events
            plan.append((node, waitables,
                         tuple((entity.handle.pointer, entity) for entity in timers),
                         tuple((entity.handle.pointer, entity) for entity in subscriptions),
                         tuple((entity.handle.pointer, entity) for entity in guards),
                         tuple((entity.handle.pointer, entity) for entity in clients),
                         tuple((entity.handle.pointer, entity) for entity in services)))
        self._wait_set = _rclpy.WaitSet(*counts, self._context.handle)
        self._plan = tuple(plan)
        self._entity_key = key
        self._executor_guards = (self._guard, self._sigint_gc)

    def _run_tasks(self) -> None:
        """Run the tasks rclpy's handlers left waiting (futures' callbacks, awaiting handlers)."""
        with self._tasks_lock:
            tasks = list(self._tasks)
        if not tasks:
            return
        for task, _, _ in reversed(tasks):
            if not task.executing() and not task.done():
                task()
                if task.exception() is not None:
                    raise task.exception()
        with self._tasks_lock:
            self._tasks = [entry for entry in self._tasks
                           if not entry[0].done() and not entry[0].cancelled()]

    def _spin_once_impl(self, timeout_sec=None, wait_condition=lambda: False) -> None:
        if self._is_shutdown or wait_condition():
            return
        self._run_tasks()
        if wait_condition():
            return
        key = self._current_key(self._node_order)
        if key != self._entity_key:
            self._rebuild(key)
        wait_set = self._wait_set
        wait_set.clear_entities()
        for node, waitables, timers, subscriptions, guards, clients, services in self._plan:
            for _, subscription in subscriptions:
                wait_set.add_subscription(subscription.handle)
            for _, client in clients:
                wait_set.add_client(client.handle)
            for _, service in services:
                wait_set.add_service(service.handle)
            for _, timer in timers:
                wait_set.add_timer(timer.handle)
            for _, guard in guards:
                wait_set.add_guard_condition(guard.handle)
            for waitable in waitables:
                waitable.add_to_wait_set(wait_set)
        for guard in self._executor_guards:
            wait_set.add_guard_condition(guard.handle)
        if isinstance(timeout_sec, TimeoutObject):
            timeout_sec = timeout_sec.timeout
        wait_set.wait(timeout_sec_to_nsec(timeout_sec))
        if self._is_shutdown:
            return
        if not self._context.ok():
            raise ExternalShutdownException()
        subscriptions_ready = set(wait_set.get_ready_entities('subscription'))
        timers_ready = set(wait_set.get_ready_entities('timer'))
        guards_ready = set(wait_set.get_ready_entities('guard_condition'))
        clients_ready = set(wait_set.get_ready_entities('client'))
        services_ready = set(wait_set.get_ready_entities('service'))
        ready_waitables = [(node, waitable) for node, waitables, *_ in self._plan
                           for waitable in waitables if waitable.is_ready(wait_set)]
        for node, waitable in ready_waitables:
            self._run_handler(waitable, node, self._take_waitable)
        for node, _, timers, subscriptions, guards, clients, services in self._plan:
            for pointer, timer in timers:
                if pointer in timers_ready and timer.handle.is_timer_ready():
                    self._call_timer(timer)
            for pointer, subscription in subscriptions:
                if pointer in subscriptions_ready:
                    self._call_subscription(subscription)
            for pointer, guard in guards:
                if pointer in guards_ready and guard.callback is not None:
                    self._call(guard, guard.callback, ())
            for pointer, client in clients:
                if pointer in clients_ready:
                    self._run_handler(client, node, self._take_client)
            for pointer, service in services:
                if pointer in services_ready:
                    self._run_handler(service, node, self._take_service)

    def _call(self, entity, callback, arguments) -> None:
        group = entity.callback_group
        if not group.beginning_execution(entity):
            return  # its group is busy (an awaiting handler): ready again at the next wait
        try:
            callback(*arguments)
        finally:
            group.ending_execution(entity)

    def _call_timer(self, timer) -> None:
        group = timer.callback_group
        if not group.beginning_execution(timer):
            return
        try:
            timer.handle.call_timer()
            timer.callback()
        finally:
            group.ending_execution(timer)

    def _call_subscription(self, subscription) -> None:
        group = subscription.callback_group
        if not group.beginning_execution(subscription):
            return
        try:
            taken = subscription.handle.take_message(subscription.msg_type, subscription.raw)
            if taken is not None:
                if subscription._callback_type is Subscription.CallbackType.MessageOnly:
                    subscription.callback(taken[0])
                else:
                    subscription.callback(*taken)
        finally:
            group.ending_execution(subscription)

    def _run_handler(self, entity, node, take) -> None:
        """Serve an entity through rclpy's own handler (a Task), as rclpy's executor does."""
        handler = self._make_handler(entity, node, take)
        handler()
        if handler.exception() is not None:
            raise handler.exception()
        if handler.done():
            with self._tasks_lock:
                self._tasks = [entry for entry in self._tasks if entry[0] is not handler]



def make_executor(name: str, context=None):
    """Return a new executor by its ``HRC_EXECUTOR`` name (see :data:`EXECUTORS`)."""
    if name == 'lean':
        return LeanExecutor(context=context)
    if name == 'rclpy':
        return SingleThreadedExecutor(context=context)
    raise ValueError(f'{EXECUTOR_VARIABLE}={name!r} is not one of {", ".join(EXECUTORS)}')


def spin_nodes(nodes, executor_name: str) -> None:
    """Serve ``nodes`` (one context) on one executor of the name given until it shuts down.

    The executor serves the nodes in the order given (each node's callbacks in rclpy's order).
    """
    executor = make_executor(executor_name, context=nodes[0].context)
    for node in nodes:
        executor.add_node(node)
    try:
        executor.spin()
    finally:
        executor.shutdown()


def executor_problem(environ=None) -> str:
    """Return why ``HRC_EXECUTOR`` cannot be used, or '' (unset means 'lean')."""
    name = (os.environ if environ is None else environ).get(EXECUTOR_VARIABLE, 'lean')
    if name not in EXECUTORS:
        return f'{EXECUTOR_VARIABLE}={name!r} is not one of {", ".join(EXECUTORS)}'
    return ''
