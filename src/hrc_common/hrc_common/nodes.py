"""Small helpers every hrc node's main() uses: --help, spin with a clean shutdown, exit codes."""

import sys

from hrc_common.params import describe, ParameterError

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


def run_node(node_factory, executable: str, summary: str, params_cls=None, args=None) -> int:
    """Run a node: answer --help, spin until Ctrl-C/SIGTERM or shutdown, then clean up.

    Bad parameters print the reasons to stderr and return EXIT_BAD_PARAMETERS. A node may define
    ``close()`` to release resources (files, PyBullet) before it is destroyed.
    """
    argv = sys.argv if args is None else args
    if wants_help(argv):
        print(help_text(executable, summary, params_cls))
        return 0

    import rclpy
    from rclpy.executors import ExternalShutdownException

    rclpy.init(args=argv)
    node = None
    code = 0
    try:
        node = node_factory()
        rclpy.spin(node)
    except ParameterError as error:
        print(f'[ERROR] [{executable}] {error}', file=sys.stderr)
        code = EXIT_BAD_PARAMETERS
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
        rclpy.try_shutdown()
    return code
