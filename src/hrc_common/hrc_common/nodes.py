"""Small helpers every hrc node's main() uses: --help, spin with a clean shutdown, exit codes."""

import os
import sys

import rclpy
from rclpy._rclpy_pybind11 import RCLError
from rclpy.executors import ExternalShutdownException

from hrc_common.params import (describe, node_parameter_problems, ParameterError,
                               parse_ros_arguments, RosArguments, set_process_arguments)

# Exit code of a node whose parameters were rejected (distinct from a crash, for the supervisor).
EXIT_BAD_PARAMETERS = 2


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

    node = None
    code = 0
    try:
        try:
            rclpy.init(args=argv)
        except Exception as error:  # rcl refuses the arguments (it says why)
            return report_bad_parameters(executable, [f'ROS refused the arguments: {error}'])
        node = node_factory()
        rclpy.spin(node)
    except ParameterError as error:
        code = report_bad_parameters(executable, error.reasons)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
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
