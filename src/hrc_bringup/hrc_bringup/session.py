"""Session runner: start the hrc graph for one case, supervise it, report at the end.

    hrc session --case 2 --seed 0            # headless, simulated human
    hrc session --case 1 --mode realtime --human auto --subject-id P07

It starts sim, agent, human and recorder as separate processes (the executables ``ros2 run``
starts) with one parameter file composed from ``params/*.yaml`` (see
hrc_common.session_plan), prints a progress line per episode, and stops everything when the
agent finishes, a node dies, or on Ctrl-C / SIGTERM, the recorder last so its bags are closed.
Then it runs the report.

This module is the run loop; each other job of the runner has its module in hrc_bringup:
``session_args`` (the command line), ``session_progress`` (the lines it prints),
``input_guard`` (a person's input lost: pause), ``practice`` (the person alone before the
condition), ``study_hooks`` (study index, NASA-TLX, owner-only files) and ``session_report``.

Live sessions (hrc_live, docs/live_study.md): ``--display`` also starts the display node (the
person's page and the experimenter's console on localhost); ``--params FILE`` merges a
parameter file such as the one ``hrc joystick setup`` writes; the operator pauses, resumes or
aborts with ``hrc operator ...`` or the console's buttons. An operator abort is a
clean stop: the bags are closed, the runner prints the command that resumes the session from
its last checkpoint (counters continue), and exits with code 3 (EXIT_OPERATOR_ABORT).

The person's time only when needed: in a realtime session the agent runs the training steps
without the person in lockstep (as fast as the graph goes) and switches the sim to realtime
for the episodes with the person (``ResetEpisode.clock_mode``); the runner prints how long the
robot practised alone and when the person joined.

Never a silent stand-in (hrc_bringup.input_guard): in realtime with ``--human device``, ``joy``
or ``auto`` the runner does not start until the input is there, and pauses the session at once
when it is lost; ``--stand-in sim`` asks for the simulated human instead.

Exit codes: 0 done, 1 a node failed, 2 bad arguments, 3 aborted by the operator, 124 timeout,
130/143 SIGINT/SIGTERM.
"""

import json
import os
import pathlib
import re
import signal
import sys
import time

from hrc_agent_node.config import AgentParams
from hrc_agent_node.strategies import pretrains_with_population
from hrc_common import paths
from hrc_common.executables import executable_path
from hrc_common.session_control import EXIT_OPERATOR_ABORT, LATEST_CHECKPOINT
from hrc_common.session_plan import compose, NODES, SessionSettings, write_session_files
import rclpy
from rclpy.context import Context
import yaml

from hrc_bringup.compose_nodes import session_composition
from hrc_bringup.input_guard import InputGuard, wait_for_input
from hrc_bringup.practice import run_practice
from hrc_bringup.session_args import parse_args, person_input, resume_command
from hrc_bringup.session_progress import Progress
from hrc_bringup.session_report import report
from hrc_bringup.study_hooks import index_session, owner_only, wait_for_tlx
from hrc_bringup.supervisor import describe_exit, Supervisor

# issue 25: seconds the runner waits for the display's address in its log before going on.
DISPLAY_ADDRESS_WAIT_S = 15.0
# Stop order: the actors first, the recorder last so it records everything and closes its bags.
STOP_ORDER = ('agent', 'human', 'sim', 'recorder')


def pretrain_if_needed(parameters: dict, run_dir):
    """Pre-train a partners-first session (cases 7, 8); return its agent settings, else None.

    ``hrc_partners.partners_first.prepare_person_session`` for a case that pre-trains; the other
    cases return None without loading torch (1-2 s of every session's start-up before the
    nodes were launched).
    """
    if not pretrains_with_population(parameters['agent']):
        return None
    from hrc_partners.partners_first import prepare_person_session  # lazy: torch
    try:
        return prepare_person_session(parameters, run_dir)
    except (ValueError, OSError) as error:
        raise ValueError(f'pre-training with simulated partners failed: {error}') from error


def write_parameters(parameters: dict, path: pathlib.Path) -> pathlib.Path:
    """Write a ROS 2 parameter file with a section per node."""
    path.write_text(yaml.safe_dump(
        {node: {'ros__parameters': values} for node, values in parameters.items()},
        sort_keys=False))
    return path


def run_session(settings: SessionSettings, options) -> int:
    """Run one session; return the exit code (0 = the agent finished the session)."""
    params_dir = pathlib.Path(options.params_dir) if options.params_dir else paths.params_dir()
    composed, problems = session_composition()     # HRC_COMPOSE (issue 24)
    if problems:
        print('\n'.join(f'session: {problem}' for problem in problems), file=sys.stderr)
        return 2
    try:
        parameters = compose(settings, params_dir)
    except (ValueError, OSError) as error:
        print(f'session: {error}', file=sys.stderr)
        return 2
    run_dir = pathlib.Path(settings.runs_dir) / settings.session_id
    if settings.subject_id:
        # issue 25: with a subject id everything the session writes is owner-only (files
        # 0600, folders 0700): the nodes inherit the mask (checkpoints, run and bag folders)
        os.umask(0o077)
    if settings.record:
        parameters['recorder']['session_config'] = str(run_dir / 'session.yaml')
    live_input = person_input(settings, options)
    if live_input:
        # Never a silent stand-in: the simulated human only when the operator asked for it.
        parameters['human']['on_input_lost'] = 'sim' if options.stand_in == 'sim' else 'pause'
    if 'human' in options.remote_nodes:
        # The station's human node is started by hand, possibly long after this runner: the
        # agent waits for it (wait_for_subscribers) as long as the runner waits for its input.
        agent = parameters['agent']
        agent['reset_timeout'] = max(float(agent['reset_timeout']), float(options.input_wait))
    if not settings.resume_from:
        # Partners first (cases 7, 8): the robot alone and with the simulated population in
        # this process first (no person: minutes), then the graph from that checkpoint.
        try:
            start = pretrain_if_needed(parameters, run_dir)
        except (ValueError, OSError) as error:
            print(f'session: {error}', file=sys.stderr)
            return 2
        if start is not None:
            parameters['agent'].update(start)
            record = json.loads((run_dir / 'pretrain.json').read_text())
            print(f'[session] pre-trained with simulated partners (no person): '
                  f'{record["episodes"]} episodes, {record["population_episodes"]} of them '
                  f'with the population, in {record["wall_seconds"]:.0f} s; the session '
                  f'continues from {start["resume_from"]}', flush=True)
            if not record['reached_person_step']:
                print("[session] the pre-training ran out of episodes before the person's "
                      'step (the robot alone did not converge): the person joins only for '
                      'the evaluation; give more --episodes', flush=True)
    params_path, _ = write_session_files(settings, parameters, run_dir, params_dir)

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
    progress = Progress(context, sys.stdout.isatty(),
                        max_training_episodes=parameters['agent'].get('max_training_episodes'),
                        evaluation_episodes=parameters['agent'].get(
                            'evaluation_episodes', AgentParams.evaluation_episodes))
    executor = rclpy.executors.SingleThreadedExecutor(context=context)
    executor.add_node(progress.node)
    guard = (InputGuard(progress.node, live_input, parameters['human'].get('device', ''),
                        options.link_timeout)
             if live_input and options.stand_in == 'none' else None)
    code = 0
    start = time.monotonic()
    started = time.strftime('%Y-%m-%dT%H:%M:%S')
    restarts = 0
    process_of = {}         # node -> the name of its process (sim+human when composed)
    try:
        if options.display:
            # issue 25: served from the start (the waiting-for-the-joystick screen included)
            supervisor.start('display', display_command(options, params_dir, run_dir))
            print_display_address(supervisor.processes['display'], executor, stop_reason)
        if live_input and not wait_for_input(
                guard or InputGuard(progress.node, live_input,
                                    parameters['human'].get('device', '')),
                executor, options.input_wait, stop_reason):
            return 2
        if options.practice:
            practice_started = time.strftime('%Y-%m-%dT%H:%M:%S')
            practice_code = run_practice(settings, options, params_dir, env, progress,
                                         executor, stop_reason)
            index_session(settings, options, 'practice', practice_started, practice_code)
            if practice_code != 0:
                return practice_code
            progress.restart()
            started = time.strftime('%Y-%m-%dT%H:%M:%S')
            if guard is not None:
                guard.resumed()  # nothing to resume: an input lost in practice is only told
        # The recorder first, so it sees the first state; the sim before the agent resets it.
        for node in ('recorder', 'sim', 'human', 'agent'):
            if node not in parameters or node in options.remote_nodes or node in process_of:
                continue
            together = [name for name in composed if name in parameters
                        and name not in options.remote_nodes] if node in composed else []
            if len(together) > 1:
                # one process, one executor (hrc_bringup.compose_nodes), named sim+human...
                supervisor.start('+'.join(together), [
                    sys.executable, '-m', 'hrc_bringup.compose_nodes', *together, '--ros-args',
                    '--params-file', str(params_path)])
                process_of.update((name, '+'.join(together)) for name in together)
                continue
            package, executable, _ = NODES[node]
            supervisor.start(node, [str(executable_path(package, executable)), '--ros-args',
                                    '--params-file', str(params_path)],
                             niceness=options.recorder_niceness if node == 'recorder' else 0)
            process_of[node] = node
        while True:
            executor.spin_once(timeout_sec=0.1)
            if stop_reason:
                print(f'[session] {stop_reason[0]} received: stopping the session', flush=True)
                code = 130 if stop_reason[0] == 'SIGINT' else 143
                break
            if guard is not None:
                guard.tick()
            if guard is not None and guard.agent_down:
                if guard.abort_requested:
                    print('[session] the operator aborted the session while it was paused '
                          '(joystick disconnected)', flush=True)
                    code = EXIT_OPERATOR_ABORT
                    break
                if guard.resume_requested:
                    restarts += 1
                    restart_agent(supervisor, parameters, settings, run_dir, restarts)
                    guard.resumed()
                    print('[session] resumed by the operator: the agent continues from the '
                          'last finished episode', flush=True)
                    continue
            finished = supervisor.exited()
            if finished:
                first = finished[0]
                if (guard is not None and guard.lost and first.name == 'agent'
                        and first.returncode == EXIT_OPERATOR_ABORT and not guard.agent_down):
                    guard.on_agent_exit()
                    print('[session] paused (joystick disconnected): waiting for the input and '
                          "the operator's resume", flush=True)
                    continue
                if guard is not None and guard.agent_down and first.name == 'agent':
                    finished = finished[1:]
                    if not finished:
                        continue
                    first = finished[0]
                if first.name == 'agent' and first.returncode == 0:
                    print('[session] the agent finished the session', flush=True)
                    if options.tlx:
                        wait_for_tlx(run_dir / 'tlx.yaml', settings.session_id, executor,
                                     options.tlx_wait, stop_reason)
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
        # a composed process stops where its last node would (the recorder still last)
        order = []
        for node in reversed(STOP_ORDER):
            if process_of.get(node, node) not in order:
                order.append(process_of.get(node, node))
        exits = supervisor.stop_all(order[::-1])
        # Let the last episode summaries arrive before closing.
        progress.close()
        executor.shutdown()
        rclpy.shutdown(context=context)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    elapsed = time.monotonic() - start
    print(f'[session] stopped after {elapsed:.1f} s: ' + ', '.join(
        f'{name} {describe_exit(returncode)}' for name, returncode in exits.items()), flush=True)
    recorder_exit = next((returncode for name, returncode in exits.items()
                          if 'recorder' in name.split('+')), 0)
    if recorder_exit not in (0, None) and code in (0, EXIT_OPERATOR_ABORT):
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
    index_session(settings, options, 'condition', started, code)
    if settings.subject_id:
        owner_only(settings, parameters)    # issue 25
    return code


def print_display_address(display, executor, stop_reason: list) -> None:
    """Print the addresses of the person's page and the console once the display serves.

    (issue 25) Read from the display's log line; its port may be chosen by the system (0).
    """
    deadline = time.monotonic() + DISPLAY_ADDRESS_WAIT_S
    while time.monotonic() < deadline and not stop_reason:
        found = re.search(r'serving the display on (http://\S+?/) ', display.tail(lines=50))
        if found:
            print(f"[session] the person's page: {found.group(1)}   the experimenter's "
                  f'console: {found.group(1)}console', flush=True)
            return
        if display.returncode is not None:
            break
        executor.spin_once(timeout_sec=0.1)
    print(f'[session] the display did not say its address within {DISPLAY_ADDRESS_WAIT_S:.0f} '
          f's: see {display.log_path}', file=sys.stderr, flush=True)


def display_command(options, params_dir: pathlib.Path, run_dir: pathlib.Path) -> list:
    """Return the command line of the display node of this session."""
    command = [str(executable_path('hrc_live', 'display_node')), '--ros-args']
    display_params = params_dir / 'display.yaml'
    if display_params.is_file():
        command += ['--params-file', str(display_params)]
    if options.display_port is not None:
        command += ['-p', f'port:={options.display_port}']
    if options.tlx:
        command += ['-p', f'tlx_file:={(run_dir / "tlx.yaml").resolve()}']
    return command


def restart_agent(supervisor: Supervisor, parameters: dict, settings: SessionSettings,
                  run_dir: pathlib.Path, restarts: int) -> None:
    """Start the agent again from the session's last checkpoint (after a paused input loss)."""
    checkpoint = (pathlib.Path(parameters['agent']['checkpoint_dir']) / settings.session_id
                  / LATEST_CHECKPOINT)
    resumed = {node: dict(values) for node, values in parameters.items()}
    if checkpoint.is_file():
        resumed['agent']['resume_from'] = str(checkpoint)
    path = write_parameters(resumed, run_dir / f'parameters-resume-{restarts}.yaml')
    old_log = supervisor.log_dir / 'agent.log'
    if old_log.is_file():
        old_log.rename(supervisor.log_dir / f'agent-before-resume-{restarts}.log')
    package, executable, _ = NODES['agent']
    supervisor.start('agent', [str(executable_path(package, executable)), '--ros-args',
                               '--params-file', str(path)])


def main(argv=None) -> int:
    """Entry point of ``hrc session``."""
    settings, options = parse_args(argv)
    return run_session(settings, options)


if __name__ == '__main__':
    sys.exit(main())
