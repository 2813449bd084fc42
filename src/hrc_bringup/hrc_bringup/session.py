"""Session runner: start the hrc graph for one case, supervise it, report at the end.

    ros2 run hrc_bringup session --case 2 --seed 0            # headless, simulated human
    ros2 run hrc_bringup session --case 1 --mode realtime --human auto --subject-id P07

It starts sim, agent, human and recorder as separate processes (the executables ``ros2 run``
starts) with one parameter file composed from ``params/*.yaml`` (see hrc_bringup.plan), prints a
progress line per episode, and stops everything when the agent finishes, a node dies, or on
Ctrl-C / SIGTERM, the recorder last so its bags are closed. Then it runs the report.

Live sessions (hrc_live): ``--display`` also starts the display node (a page on localhost);
``--params FILE`` merges a parameter file such as the one ``joystick_setup`` writes; the
operator pauses, resumes or aborts with ``ros2 run hrc_live operator ...``. An operator abort
is a clean stop: the bags are closed, the runner prints the command that resumes the session
from its last checkpoint (counters continue), and exits with code 3 (EXIT_OPERATOR_ABORT).

Exit codes: 0 done, 1 a node failed, 2 bad arguments, 3 aborted by the operator, 124 timeout,
130/143 SIGINT/SIGTERM.
"""

import argparse
import os
import pathlib
import shlex
import signal
import subprocess
import sys
import time

from hrc_common.contract import phase_label
from hrc_common.session_control import EXIT_OPERATOR_ABORT, LATEST_CHECKPOINT
import yaml

from hrc_bringup.plan import (compose, NODES, new_session_id, parse_override, SessionSettings,
                              write_session_files)
from hrc_bringup.supervisor import describe_exit, Supervisor

# Stop order: the actors first, the recorder last so it records everything and closes its bags.
STOP_ORDER = ('agent', 'human', 'sim', 'recorder')


def default_params_dir() -> pathlib.Path:
    """Return the parameter files: ./params in a checkout, else the installed ones."""
    local = pathlib.Path('params')
    if (local / 'sim.yaml').is_file():
        return local
    from ament_index_python.packages import get_package_share_directory
    return pathlib.Path(get_package_share_directory('hrc_bringup')) / 'params'


def parse_args(argv=None):
    """Parse the command line into (SessionSettings, options)."""
    parser = argparse.ArgumentParser(
        prog='session', description='Run one hrc session (one case, one seed): sim, agent, '
        'human and recorder as supervised processes, then the report.')
    parser.add_argument('--case', type=int, default=2, help='paper case 1..6 (default 2)')
    parser.add_argument('--seed', type=int, default=0, help='session seed (default 0)')
    parser.add_argument('--mode', choices=('lockstep', 'realtime'), default='lockstep',
                        help='lockstep: as fast as the graph allows (headless); realtime: '
                        'every 0.2 s of wall time (a person at the joystick)')
    parser.add_argument('--human', dest='human_input', default='sim',
                        choices=('sim', 'auto', 'device', 'joy'),
                        help='human input (default sim: the simulated human)')
    parser.add_argument('--profile', dest='human_profile', default='',
                        help='simulated-human profile (params/sim_human.yaml)')
    parser.add_argument('--episodes', dest='training_episodes', type=int, default=0,
                        help='max training episodes (default: params/agent.yaml)')
    parser.add_argument('--eval-episodes', dest='evaluation_episodes', type=int, default=-1,
                        help='evaluation episodes (default: params/agent.yaml)')
    parser.add_argument('--session-id', default='', help='default: case<N>-seed<S>-<time>')
    parser.add_argument('--bags-dir', default='bags', help='bags go to <bags-dir>/<session>')
    parser.add_argument('--runs-dir', default='runs',
                        help='logs, parameters, checkpoints and report go to <runs-dir>')
    parser.add_argument('--params-dir', default=None, help='default: ./params or installed')
    parser.add_argument('--no-record', dest='record', action='store_false',
                        help='do not start the recorder')
    parser.add_argument('--resume-from', default='', help='agent checkpoint to resume')
    parser.add_argument('--subject-id', default='', help='pseudonymous subject id (bag metadata)')
    parser.add_argument('--notes', default='', help='free-text notes (bag metadata)')
    parser.add_argument('--set', dest='overrides', action='append', default=[],
                        metavar='NODE.PARAM=VALUE', help='override a node parameter (repeatable)')
    parser.add_argument('--params', dest='params_files', action='append', default=[],
                        metavar='FILE', help='a ROS 2 parameter file whose node sections '
                        'override params/*.yaml, e.g. the joystick_setup output (repeatable; '
                        '--set wins)')
    parser.add_argument('--display', action='store_true',
                        help='also start the display node (hrc_live): the page for the person '
                        'on http://127.0.0.1:<port>/ (params/display.yaml)')
    parser.add_argument('--domain-id', type=int, default=None,
                        help='ROS_DOMAIN_ID of the session (default: the environment)')
    parser.add_argument('--no-report', dest='report', action='store_false',
                        help='skip the report at the end')
    parser.add_argument('--recorder-niceness', type=int, default=10, choices=range(0, 20),
                        metavar='0..19', help='run the recorder at this lower CPU priority '
                        '(default 10): it buffers and catches up between episodes, so it does '
                        'not slow the control loop; 0 = same priority as the nodes')
    parser.add_argument('--timeout', type=float, default=0.0,
                        help='stop the session after this many wall seconds (0 = none)')
    options = parser.parse_args(argv)
    options.argv = list(sys.argv[1:] if argv is None else argv)
    overrides = {}
    for path in options.params_files:
        try:
            overrides.update(file_overrides(path))
        except (OSError, ValueError, yaml.YAMLError) as error:
            parser.error(f'--params {path}: {error}')
    for text in options.overrides:
        try:
            node, name, value = parse_override(text)
        except ValueError as error:
            parser.error(str(error))
        overrides[f'{node}.{name}'] = value
    settings = SessionSettings(
        case=options.case, seed=options.seed, mode=options.mode,
        human_input=options.human_input, human_profile=options.human_profile,
        training_episodes=options.training_episodes,
        evaluation_episodes=options.evaluation_episodes, session_id=options.session_id,
        bags_dir=options.bags_dir, runs_dir=options.runs_dir, record=options.record,
        resume_from=options.resume_from, subject_id=options.subject_id, notes=options.notes,
        overrides=overrides)
    if not settings.session_id:
        settings.session_id = new_session_id(settings)
    reasons = settings.check()
    if settings.subject_id and settings.subject_id.lower() in settings.session_id.lower():
        # Bag and run folders are named after the session id: no personal data in file names.
        reasons.append('the session id must not contain the subject id (it names files)')
    if reasons:
        parser.error('; '.join(reasons))
    return settings, options


def file_overrides(path) -> dict:
    """Return {'node.name': value} of the node sections of a ROS 2 parameter file."""
    document = yaml.safe_load(pathlib.Path(path).read_text()) or {}
    if not isinstance(document, dict):
        raise ValueError('not a parameter file (a mapping of node sections)')
    overrides = {}
    for node, section in document.items():
        if node not in NODES:
            raise ValueError(f'section {node!r} is not one of the nodes {sorted(NODES)}')
        values = (section or {}).get('ros__parameters') or {}
        overrides.update({f'{node}.{name}': value for name, value in values.items()})
    return overrides


def resume_command(options, session_id: str, checkpoint: pathlib.Path) -> str:
    """Return the command line that resumes this session from ``checkpoint``."""
    args, skip = [], False
    for arg in options.argv:
        if skip:
            skip = False
            continue
        if arg in ('--resume-from', '--session-id'):
            skip = True
            continue
        if arg.startswith(('--resume-from=', '--session-id=')):
            continue
        args.append(arg)
    return shlex.join(['ros2', 'run', 'hrc_bringup', 'session', *args, '--session-id',
                       session_id, '--resume-from', str(checkpoint)])


class Progress:
    """Listens to /hrc/session and /hrc/episode and prints what happens (one rclpy node)."""

    def __init__(self, context, interactive: bool):
        import rclpy

        from hrc_common import qos, topics
        from hrc_msgs.msg import EpisodeSummary, SessionStatus

        self.node = rclpy.create_node('session_runner', context=context)
        self.interactive = interactive
        self.status = None
        self.episodes = []
        self.node.create_subscription(SessionStatus, topics.SESSION, self._on_status,
                                      qos.SESSION_QOS)
        self.node.create_subscription(EpisodeSummary, topics.EPISODE, self._on_episode,
                                      qos.EPISODE_QOS)

    def _on_status(self, status):
        # Announce what changes the task for the team; the training <-> updating toggles between
        # episodes are shown on the progress line only.
        def milestone(status):
            phase = phase_label(status.phase, '?')
            return (status.training_step, status.human_involved,
                    phase if phase not in ('training', 'updating') else 'training')

        changed = self.status is None or milestone(status) != milestone(self.status)
        self.status = status
        if changed:
            self._print(f'[session] case {status.case_id} {status.strategy}: training step '
                        f'{status.training_step + 1}/{max(status.training_step_count, 1)}, '
                        f'phase {milestone(status)[2]}, human '
                        f'{"involved" if status.human_involved else "not involved"}, robot '
                        f'subtasks {list(status.robot_subtasks)}, human subtasks '
                        f'{list(status.human_subtasks)}', permanent=True)

    def _on_episode(self, summary):
        if any(seen.episode == summary.episode for seen in self.episodes):
            return
        self.episodes.append(summary)
        human_episodes = sum(s.human_involved for s in self.episodes if not s.evaluation)
        steps = max(self.status.training_step_count, 1) if self.status else 1
        case = self.status.case_id if self.status else summary.case_id
        self._print(f'[case {case} | step {summary.training_step + 1}/{steps} | episode '
                    f'{summary.episode:3d} | {"evaluation" if summary.evaluation else "training"}'
                    f'] return {summary.episode_return:7.1f}  error slider '
                    f'{summary.slider_error:.3f} m  pendulum {summary.pendulum_error:.3f} rad  '
                    f'ball {summary.ball_error:.3f} m  human '
                    f'{"yes" if summary.human_involved else "no "} ({human_episodes} so far)'
                    + ('  converged' if summary.converged else ''),
                    permanent=not self.interactive or summary.evaluation or summary.converged)

    def _print(self, line, permanent=True):
        """Print a line; on a terminal, a non-permanent line is overwritten by the next one."""
        if self.interactive:
            print('\r\033[K' + line, end='\n' if permanent else '', flush=True)
        else:
            print(line, flush=True)

    def close(self):
        """Destroy the node."""
        self.node.destroy_node()


def run_session(settings: SessionSettings, options) -> int:
    """Run one session; return the exit code (0 = the agent finished the session)."""
    import rclpy
    from rclpy.context import Context

    from hrc_common.executables import executable_path

    params_dir = pathlib.Path(options.params_dir) if options.params_dir else default_params_dir()
    try:
        parameters = compose(settings, params_dir)
    except (ValueError, OSError) as error:
        print(f'session: {error}', file=sys.stderr)
        return 2
    run_dir = pathlib.Path(settings.runs_dir) / settings.session_id
    if settings.record:
        parameters['recorder']['session_config'] = str(run_dir / 'session.yaml')
    params_path, _ = write_session_files(settings, parameters, run_dir)

    env = dict(os.environ)
    if options.domain_id is not None:
        env['ROS_DOMAIN_ID'] = str(options.domain_id)
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    # A resumed session keeps the logs of the run it continues.
    logs = 'logs' if not settings.resume_from else time.strftime('logs-resumed-%Y%m%d-%H%M%S')
    supervisor = Supervisor(run_dir / logs, env)
    print(f'[session] {settings.session_id}: case {settings.case}, seed {settings.seed}, '
          f'{settings.mode}, human input {settings.human_input}; logs and parameters in '
          f'{run_dir}' + (f', bags in {pathlib.Path(settings.bags_dir) / settings.session_id}'
                          if settings.record else ''), flush=True)

    stop_reason = []

    def on_signal(signum, frame):
        stop_reason.append(signal.Signals(signum).name)

    previous = {sig: signal.signal(sig, on_signal) for sig in (signal.SIGINT, signal.SIGTERM)}
    context = Context()
    rclpy.init(context=context, domain_id=options.domain_id,
               signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    progress = Progress(context, sys.stdout.isatty())
    executor = rclpy.executors.SingleThreadedExecutor(context=context)
    executor.add_node(progress.node)
    code = 0
    start = time.monotonic()
    try:
        # The recorder first, so it sees the first state; the sim before the agent resets it.
        for node in ('recorder', 'sim', 'human', 'agent'):
            if node not in parameters:
                continue
            package, executable, _ = NODES[node]
            supervisor.start(node, [str(executable_path(package, executable)), '--ros-args',
                                    '--params-file', str(params_path)],
                             niceness=options.recorder_niceness if node == 'recorder' else 0)
        if options.display:
            display_params = params_dir / 'display.yaml'
            supervisor.start('display', [str(executable_path('hrc_live', 'display_node'))] + (
                ['--ros-args', '--params-file', str(display_params)]
                if display_params.is_file() else []))
            print(f'[session] display: see {run_dir / logs / "display.log"} for its address '
                  f'(http://127.0.0.1:<port>/)', flush=True)
        while True:
            executor.spin_once(timeout_sec=0.1)
            if stop_reason:
                print(f'[session] {stop_reason[0]} received: stopping the session', flush=True)
                code = 130 if stop_reason[0] == 'SIGINT' else 143
                break
            finished = supervisor.exited()
            if finished:
                first = finished[0]
                if first.name == 'agent' and first.returncode == 0:
                    print('[session] the agent finished the session', flush=True)
                elif first.name == 'agent' and first.returncode == EXIT_OPERATOR_ABORT:
                    message = progress.status.message if progress.status else ''
                    print(f'[session] the operator aborted the session ({message}); stopping '
                          f'the other nodes and closing the bags', flush=True)
                    code = EXIT_OPERATOR_ABORT
                else:
                    print(f'[session] node {first.name} stopped unexpectedly '
                          f'({describe_exit(first.returncode)}); stopping the session. Last '
                          f'output of {first.name}:\n{first.tail()}', file=sys.stderr, flush=True)
                    code = 1
                break
            if options.timeout and time.monotonic() - start > options.timeout:
                print(f'[session] timeout of {options.timeout:.0f} s reached: stopping',
                      file=sys.stderr, flush=True)
                code = 124
                break
    finally:
        exits = supervisor.stop_all(STOP_ORDER)
        # Let the last episode summaries arrive before closing.
        progress.close()
        executor.shutdown()
        rclpy.shutdown(context=context)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    elapsed = time.monotonic() - start
    print(f'[session] stopped after {elapsed:.1f} s: ' + ', '.join(
        f'{name} {describe_exit(returncode)}' for name, returncode in exits.items()), flush=True)
    if exits.get('recorder', 0) not in (0, None) and code in (0, EXIT_OPERATOR_ABORT):
        print('[session] the recorder did not exit cleanly: check its log', file=sys.stderr)
        code = 1
    if code == EXIT_OPERATOR_ABORT:
        checkpoint = (pathlib.Path(parameters['agent']['checkpoint_dir']) / settings.session_id
                      / LATEST_CHECKPOINT)
        if checkpoint.is_file():
            print(f'[session] to resume from the last finished episode (counters continue):\n'
                  f'  {resume_command(options, settings.session_id, checkpoint)}', flush=True)
        else:
            print('[session] no episode had finished: there is no checkpoint to resume from',
                  flush=True)
    if settings.record and options.report and (code == 0 or progress.episodes):
        report(settings, run_dir)
    return code


def report(settings: SessionSettings, run_dir: pathlib.Path) -> None:
    """Run the report CLI on the session's bags and print its Table II."""
    from hrc_common.executables import executable_path

    bag_dir = pathlib.Path(settings.bags_dir) / settings.session_id
    out_dir = run_dir / 'report'
    result = subprocess.run([str(executable_path('hrc_bag', 'hrc_report')), str(bag_dir),
                             '--out', str(out_dir)], capture_output=True, text=True)
    print(result.stdout, end='')
    if result.returncode != 0:
        print(f'[session] report failed ({describe_exit(result.returncode)}):\n{result.stderr}',
              file=sys.stderr)
        return
    print(f'[session] bags: {bag_dir}   report and figures: {out_dir}', flush=True)


def main(argv=None) -> int:
    """Entry point of ``ros2 run hrc_bringup session``."""
    settings, options = parse_args(argv)
    return run_session(settings, options)


if __name__ == '__main__':
    sys.exit(main())
