"""Small helpers every hrc node's main() uses: --help, spin with a clean shutdown, exit codes.

Also :class:`DrainedNode`, a node whose subscriptions its own timer drains in batches. The
executor the nodes spin on is :mod:`hrc_common.executors` (``HRC_EXECUTOR``), the realtime
scheduling option :mod:`hrc_common.realtime` (``HRC_REALTIME_PRIORITY``).
"""

import os
import sys

import rclpy
from rclpy._rclpy_pybind11 import RCLError
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.subscription import Subscription

from hrc_common.executors import EXECUTOR_VARIABLE, executor_problem, spin_nodes
from hrc_common.qos import NO_SUBSCRIPTION_EVENTS
from hrc_common.params import describe, ParameterError
from hrc_common.params_arguments import (node_parameter_problems, parse_ros_arguments,
                                         RosArguments, set_process_arguments)
from hrc_common.realtime import apply_realtime_priority, realtime_priority_of

# Exit code of a node whose parameters were rejected (distinct from a crash, for the supervisor).
EXIT_BAD_PARAMETERS = 2


class DrainedNode(Node):
    """A node with subscriptions no executor waits on: the node takes their messages itself.

    A subscription made with :meth:`create_drained_subscription` is left out of
    :attr:`subscriptions`, what every executor (rclpy's and :class:`LeanExecutor`) waits on, so a
    message does not wake the process for an executor turn; the node takes what waited with
    :func:`take_waiting`, from a timer, in batches (the recorder; the session runner's watch of
    the human's input source). The subscription is the node's all the same: the ROS graph, QoS
    matching and ``destroy_node`` see it (a turn per message was most of a reader's cost).
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


def closing_log(node, level: str, text: str) -> None:
    """Log ``text`` while a node closes: to /rosout while the context lives, else to stderr.

    Ctrl-C shuts the context down before the nodes close (rclpy's signal handler), and a
    logger then fails to publish to /rosout ("publisher's context is invalid") on top of the
    line; the line goes to the terminal alone, in the logger's form.
    """
    if rclpy.ok():
        getattr(node.get_logger(), level)(text)
    else:
        print(f'[{level.upper()}] [{node.get_name()}]: {text}', file=sys.stderr, flush=True)


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
        # HRC_EXECUTOR: 'lean' unless set; 'rclpy' is the escape hatch kept while the lean
        # executor leans on rclpy's internals (hrc_common.executors)
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
