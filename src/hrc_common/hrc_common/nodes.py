"""Small helpers every hrc node's main() uses: --help, spin with a clean shutdown, exit codes.

Also the executor the nodes spin on (:class:`LeanExecutor`, chosen by ``HRC_EXECUTOR``): the
lockstep graph makes one executor turn per message in each node, so the executor's own Python
work per turn bounds the graph's rate (issue 24: rclpy's wait-set rebuild was 48-58% of the sim's
and the human node's busy samples).

The realtime scheduling option (``HRC_REALTIME_PRIORITY``, off by default) puts a node process's
threads on SCHED_FIFO, so the timing-critical nodes of a realtime session preempt every
ordinarily scheduled process the moment a timer or a message wakes them (see
:func:`apply_realtime_priority`).
"""

import os
import sys

import rclpy
from rclpy._rclpy_pybind11 import RCLError
from rclpy.executors import (ExternalShutdownException, SingleThreadedExecutor,
                             TimeoutObject)
from rclpy.experimental import EventsExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.subscription import Subscription
from rclpy.utilities import timeout_sec_to_nsec

from hrc_common.contract import REALTIME_SWITCH_INTERVAL_S
from hrc_common.qos import NO_SUBSCRIPTION_EVENTS
from hrc_common.params import describe, ParameterError
from hrc_common.params_arguments import (node_parameter_problems, parse_ros_arguments,
                                         RosArguments, set_process_arguments)

# Exit code of a node whose parameters were rejected (distinct from a crash, for the supervisor).
EXIT_BAD_PARAMETERS = 2


# HRC_EXECUTOR: the executor run_node spins a node on. 'lean' (default): LeanExecutor;
# 'rclpy': rclpy's SingleThreadedExecutor (what every node used before issue 24; same callbacks
# in the same order, only slower); 'events': rclpy.experimental.EventsExecutor (experimental:
# no guard conditions in Jazzy's, see docs/engines.md "Executors").
EXECUTOR_VARIABLE = 'HRC_EXECUTOR'
EXECUTORS = ('lean', 'rclpy', 'events')


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


class DrainedNode(Node):
    """A node with subscriptions no executor waits on: the node takes their messages itself.

    A subscription made with :meth:`create_drained_subscription` is left out of
    :attr:`subscriptions`, what every executor (rclpy's and :class:`LeanExecutor`) waits on, so a
    message does not wake the process for an executor turn; the node takes what waited with
    :func:`take_waiting`, from a timer, in batches (the recorder; the session runner's watch of
    the human's input source). The subscription is the node's all the same: the ROS graph, QoS
    matching and ``destroy_node`` see it (issue 24: a turn per message was most of a reader's
    cost).
    """

    def create_drained_subscription(self, msg_type, topic: str, qos_profile,
                                    raw=False) -> Subscription:
        """Create a subscription that only :func:`take_waiting` reads (no callback).

        Without QoS event handlers: an executor would wait on those (a subscription's events
        are its node's waitables), and they kept the session runner's rclpy executor turning
        without pause (measured: 1.7-2.6 ms of CPU per lockstep step with them, 0.08-0.13
        without).
        """
        subscription = self.create_subscription(
            msg_type, topic, _never_called, qos_profile, raw=raw,
            event_callbacks=NO_SUBSCRIPTION_EVENTS)
        self._drained_subscriptions = getattr(self, '_drained_subscriptions', set())
        self._drained_subscriptions.add(subscription)
        return subscription

    @property
    def subscriptions(self):
        """Return the subscriptions an executor serves: not the drained ones."""
        drained = getattr(self, '_drained_subscriptions', ())
        return [subscription for subscription in super().subscriptions
                if subscription not in drained]


def _never_called(_message) -> None:
    """Do nothing: a drained subscription's messages are read by take_waiting."""


def take_waiting(subscription: Subscription, limit: int):
    """Yield (message, info) of up to ``limit`` messages waiting in ``subscription``, in order.

    The message is bytes for a raw subscription; ``info`` rclpy's dict (``received_timestamp``,
    ``source_timestamp``, ``publication_sequence_number``). ``limit`` (the history's depth)
    keeps a publisher faster than the caller from holding it here.
    """
    with subscription.handle:   # as rclpy's executor: the handle stays alive while in use
        take = subscription.handle.take_message
        for _ in range(limit):
            taken = take(subscription.msg_type, subscription.raw)
            if taken is None:
                return
            yield taken


def make_executor(name: str, context=None):
    """Return a new executor by its ``HRC_EXECUTOR`` name (see :data:`EXECUTORS`)."""
    if name == 'lean':
        return LeanExecutor(context=context)
    if name == 'rclpy':
        return SingleThreadedExecutor(context=context)
    if name == 'events':
        return EventsExecutor(context=context)
    raise ValueError(f'{EXECUTOR_VARIABLE}={name!r} is not one of {", ".join(EXECUTORS)}')


# HRC_REALTIME_PRIORITY: unset, empty or 0 = off (the default: the kernel's ordinary scheduler, as
# before); 1..99 = run the node process's threads on SCHED_FIFO at that priority (a realtime
# lab's setting for the timing-critical nodes; needs root or CAP_SYS_NICE, else a log line says
# it was not permitted and the node runs as before).
REALTIME_PRIORITY_VARIABLE = 'HRC_REALTIME_PRIORITY'
REALTIME_PRIORITY_RANGE = (1, 99)   # SCHED_FIFO's priorities on Linux
# The interpreter's thread switch interval while realtime scheduling is on:
# hrc_common.contract.REALTIME_SWITCH_INTERVAL_S (imported above; the agent's learner uses it too).


def realtime_priority_of(environ=None) -> tuple:
    """Return (priority, problem) of ``HRC_REALTIME_PRIORITY``: (0, '') when off or unset."""
    text = (os.environ if environ is None else environ).get(REALTIME_PRIORITY_VARIABLE, '')
    text = text.strip()
    if text in ('', '0'):
        return 0, ''
    low, high = REALTIME_PRIORITY_RANGE
    try:
        priority = int(text)
    except ValueError:
        priority = None
    if priority is None or not low <= priority <= high:
        return 0, (f'{REALTIME_PRIORITY_VARIABLE}={text!r} is not a SCHED_FIFO priority '
                   f'{low}..{high} (or 0 / unset: off)')
    return priority, ''


def process_thread_ids() -> list:
    """Return the kernel ids of this process's threads (Linux: /proc/self/task)."""
    return sorted(int(name) for name in os.listdir('/proc/self/task'))


def apply_realtime_priority(priority: int, thread_ids=None, scheduler=None) -> str:
    """Put this process's threads on SCHED_FIFO at ``priority``; return a line for the log.

    Every thread alive now is switched (the caller's, and the middleware's receive and writer
    threads, which deliver the messages the node waits on), each with SCHED_RESET_ON_FORK:
    threads started later (the agent's learner thread, a PPO update's worker threads) run on
    the ordinary scheduler, so a long computation cannot hold a core at realtime priority. Not
    permitted (no root or CAP_SYS_NICE), or not Linux: the line says so; nothing is changed and
    nothing is raised. ``scheduler`` (os.sched_setscheduler by default) is for tests.
    """
    if priority <= 0:
        return ''
    set_scheduler = scheduler or getattr(os, 'sched_setscheduler', None)
    if set_scheduler is None or not hasattr(os, 'SCHED_FIFO'):
        return (f'{REALTIME_PRIORITY_VARIABLE}={priority}: realtime scheduling is not available '
                f'on this system; running on the ordinary scheduler')
    policy = os.SCHED_FIFO | getattr(os, 'SCHED_RESET_ON_FORK', 0)
    thread_ids = process_thread_ids() if thread_ids is None else thread_ids
    switched = []
    for thread_id in thread_ids:
        try:
            set_scheduler(thread_id, policy, os.sched_param(priority))
        except ProcessLookupError:
            continue   # the thread ended meanwhile
        except OSError as error:
            if switched:   # undo: all or nothing, so the log line is the whole truth
                for done in switched:
                    try:
                        set_scheduler(done, os.SCHED_OTHER, os.sched_param(0))
                    except OSError:
                        pass
            return (f'{REALTIME_PRIORITY_VARIABLE}={priority}: SCHED_FIFO not permitted '
                    f'({error.strerror or error}; it needs root or CAP_SYS_NICE, e.g. '
                    f'`sudo setcap cap_sys_nice+ep` on the python binary or an rtprio limit '
                    f'in /etc/security/limits.conf); running on the ordinary scheduler')
        switched.append(thread_id)
    sys.setswitchinterval(REALTIME_SWITCH_INTERVAL_S)
    return (f'{REALTIME_PRIORITY_VARIABLE}={priority}: {len(switched)} thread(s) on SCHED_FIFO '
            f'priority {priority} (threads started later: ordinary scheduler); Python switch '
            f'interval {REALTIME_SWITCH_INTERVAL_S * 1000:g} ms')


# Wait (s) of one turn of rclpy's EventsExecutor in spin(): see spin().
EVENTS_TURN_S = 0.1


def spin(node, executor_name: str) -> None:
    """Serve ``node`` on the executor named until its context shuts down (see spin_nodes)."""
    spin_nodes([node], executor_name)


def spin_nodes(nodes, executor_name: str) -> None:
    """Serve ``nodes`` (one context) on one executor of the name given until it shuts down.

    The executor serves the nodes in the order given (each node's callbacks in rclpy's order).

    rclpy's EventsExecutor (Jazzy, rclpy 7.1) is turned with a timeout: its ``spin()`` and its
    ``spin_once()`` without a timeout never run a callback and starve every other Python thread
    (bench/events_executor_hang.py reproduces it in a few lines); that is why the graph hung with
    every node on it (issue 24). ``spin_once(timeout_sec)`` serves callbacks as they come. It
    has no guard conditions ("Guard conditions not supported"): a node with one (the human
    node's stick watcher) is refused with a ParameterError (exit code 2).
    """
    for node in nodes:
        if executor_name == 'events' and any(True for _ in node.guards):
            raise ParameterError(f"{EXECUTOR_VARIABLE}=events: rclpy's EventsExecutor has no "
                                 f'guard conditions (Jazzy) and node {node.get_name()!r} uses '
                                 f'one; use lean or rclpy')
    context = nodes[0].context
    executor = make_executor(executor_name, context=context)
    for node in nodes:
        executor.add_node(node)
    try:
        if executor_name == 'events':
            while context.ok():
                executor.spin_once(timeout_sec=EVENTS_TURN_S)
        else:
            executor.spin()
    finally:
        executor.shutdown()


def executor_problem(environ=None) -> str:
    """Return why ``HRC_EXECUTOR`` cannot be used, or '' (unset means 'lean')."""
    name = (os.environ if environ is None else environ).get(EXECUTOR_VARIABLE, 'lean')
    if name not in EXECUTORS:
        return f'{EXECUTOR_VARIABLE}={name!r} is not one of {", ".join(EXECUTORS)}'
    return ''


def help_text(executable: str, summary: str, params_cls=None) -> str:
    """Return the --help text of a node executable."""
    text = [f'usage: ros2 run <package> {executable} [--ros-args -p name:=value '
            f'--params-file params/<node>.yaml -r from:=to ...]', '', summary]
    if params_cls is not None:
        text += ['', 'parameters:', describe(params_cls)]
    return '\n'.join(text)


def wants_help(argv) -> bool:
    """Return True when the user asked for --help before any --ros-args section."""
    user_args = argv[1:argv.index('--ros-args')] if '--ros-args' in argv else argv[1:]
    return '-h' in user_args or '--help' in user_args


def report_bad_parameters(executable: str, reasons) -> int:
    """Print every reason (one a line) to stderr; return EXIT_BAD_PARAMETERS."""
    reasons = list(reasons)
    lines = [f'[ERROR] [{executable}] parameters rejected ({len(reasons)} '
             f'reason{"s" if len(reasons) != 1 else ""}):']
    lines += [f'  - {reason}' for reason in reasons]
    print('\n'.join(lines), file=sys.stderr, flush=True)
    return EXIT_BAD_PARAMETERS


def run_node(node_factory, executable: str, summary: str, params_cls=None, args=None) -> int:
    """Run a node: answer --help, spin until Ctrl-C/SIGTERM or shutdown, then clean up.

    Bad parameters print every reason to stderr and return EXIT_BAD_PARAMETERS: the command
    line and every --params-file are checked before ``rclpy.init`` (which would otherwise fail
    with a traceback), then the node's own section and names when the node declares its
    parameters (:func:`hrc_common.params.declare_parameters`). A node may define ``close()`` to
    release resources (files, PyBullet) before it is destroyed.
    """
    return run_nodes([node_factory], executable, summary, params_cls, args)


def run_nodes(node_factories, executable: str, summary: str, params_cls=None,
              args=None) -> int:
    """Run several nodes in this process on one executor (a component container), as run_node.

    The nodes are made in the order given and served in that order; each reads its own section
    of the --params-file (by node name). ``params_cls`` (one parameter class) checks the ``-p``
    names of the command line before start; give None when the nodes' classes differ (each node
    then rejects the names it does not know when it declares its parameters). On the way out
    every node made is closed and destroyed, the last made first.
    """
    argv = list(sys.argv if args is None else args)
    if wants_help(argv):
        try:
            print(help_text(executable, summary, params_cls), flush=True)
        except BrokenPipeError:   # `... --help | head`: the reader left, nothing to report
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0

    set_process_arguments(argv)
    arguments = parse_ros_arguments(argv)
    if arguments.problems:
        reasons = list(arguments.problems)
        if params_cls is not None:   # -p names can be checked without the node
            reasons += node_parameter_problems(RosArguments(overrides=arguments.overrides),
                                               '', '/', params_cls)
        return report_bad_parameters(executable, reasons)
    environment_problems = [problem for problem in (executor_problem(),
                                                     realtime_priority_of()[1]) if problem]
    if environment_problems:
        return report_bad_parameters(executable, environment_problems)

    nodes = []
    code = 0
    try:
        try:
            rclpy.init(args=argv)
        except Exception as error:  # rcl refuses the arguments (it says why)
            return report_bad_parameters(executable, [f'ROS refused the arguments: {error}'])
        reasons = []
        for node_factory in node_factories:
            try:
                nodes.append(node_factory())
            except ParameterError as error:     # the other nodes' reasons too, at once
                reasons += error.reasons
        if reasons:
            raise ParameterError('; '.join(reasons), reasons)
        # After the nodes are made, so the middleware's threads exist and are switched too.
        scheduling = apply_realtime_priority(realtime_priority_of()[0])
        if scheduling:
            logger = nodes[0].get_logger()
            (logger.info if 'SCHED_FIFO priority' in scheduling else logger.warning)(scheduling)
        spin_nodes(nodes, os.environ.get(EXECUTOR_VARIABLE, 'lean'))
    except ParameterError as error:
        code = report_bad_parameters(executable, error.reasons)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except RCLError:
        # Ctrl-C/SIGTERM while a node was still being made: rclpy's handler shut the context
        # down under it and rcl refuses the next entity ("context is invalid"). That is a
        # stop, not a failure; any other rcl error (context still valid) is one.
        if rclpy.ok():
            raise
    finally:
        for node in reversed(nodes):
            close = getattr(node, 'close', None)
            if close is not None:
                close()
            node.destroy_node()
        # The SIGINT/SIGTERM handler may shut the context down at any moment (a check-then-act
        # race with rclpy.ok()); try_shutdown tolerates a context already shut down.
        try:
            rclpy.try_shutdown()
        except RCLError:
            pass  # shut down by the signal handler between try_shutdown's check and its call
    return code
