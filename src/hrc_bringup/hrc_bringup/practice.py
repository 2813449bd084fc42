"""The practice before a live condition: the person alone on their degree of freedom.

The runner starts the practice's graph (sim, human node, recorder, and the agent with
``practice_episodes``) and waits for the agent to finish it; the agent announces the practice on
/hrc/session, resets the sim for each episode and labels each episode practice
(``hrc_agent_node.practice``), so it is the one publisher of /hrc/session here as in the
condition.
"""

from dataclasses import replace
import pathlib
import sys
import time

from hrc_common.executables import executable_path
from hrc_common.session_control import EXIT_OPERATOR_ABORT
from hrc_common.session_plan import compose, NODES, SessionSettings, write_session_files
from hrc_msgs.msg import EpisodeSummary

from hrc_bringup.session_args import person_input
from hrc_bringup.session_progress import Progress
from hrc_bringup.supervisor import describe_exit, Supervisor

# The recorder first so it sees the first state; the sim before the agent resets it.
START_ORDER = ('recorder', 'sim', 'human', 'agent')
STOP_ORDER = ('agent', 'human', 'sim', 'recorder')


def wait_for_closed_episode(recorder, episode: int, executor, stop_reason: list,
                            timeout: float = 30.0) -> bool:
    """Wait until the recorder closed the file of ``episode`` (its log says so).

    The agent's EpisodeSummary closes it; the recorder may lag behind the agent's exit, and
    stopping it earlier would lose the messages still queued.
    """
    deadline = time.monotonic() + timeout
    mark = f'episode {episode}: closed'
    while time.monotonic() < deadline and not stop_reason:
        if mark in recorder.tail(lines=50) or recorder.returncode is not None:
            return True
        executor.spin_once(timeout_sec=0.2)
    return False


def run_practice(settings: SessionSettings, options, params_dir: pathlib.Path, env: dict,
                 progress: Progress, executor, stop_reason: list) -> int:
    """Run the practice: the person alone on their degree of freedom, realtime, no robot.

    The sim (waiting for no robot), the human node and the recorder run as in the condition;
    the agent runs the ``options.practice`` episodes (parameter ``practice_episodes``: it
    announces them, resets the sim in realtime with its ``episode_break`` between them, and
    exits 0 after the last). Recorded as the session ``<session-id>-practice``. Returns the
    exit code (0 = every practice episode ran).
    """
    practice = replace(settings, session_id=f'{settings.session_id}-practice', resume_from='')
    parameters = compose(practice, params_dir)
    parameters['agent'].update(practice_episodes=options.practice, checkpoint_dir='')
    parameters['sim'].update(start_on_launch=False, auto_reset=False, max_episodes=0,
                             expected_actors=['human'])
    if person_input(settings, options):
        parameters['human']['on_input_lost'] = ('sim' if options.stand_in == 'sim'
                                                else 'pause')
    run_dir = pathlib.Path(settings.runs_dir) / practice.session_id
    if settings.record:
        parameters['recorder']['session_config'] = str(run_dir / 'session.yaml')
    params_path, _ = write_session_files(practice, parameters, run_dir, params_dir)
    supervisor = Supervisor(run_dir / 'logs', env)
    human_dof = parameters['human']['dof']

    def practised() -> int:
        return sum(1 for summary in progress.episodes
                   if summary.kind == EpisodeSummary.KIND_PRACTICE)

    print(f'[session] practice: {options.practice} episodes of the person alone on the '
          f'{human_dof} (realtime, the robot does not act), recorded as {practice.session_id}',
          flush=True)
    code = 0
    try:
        for name in START_ORDER:
            if name in parameters:
                package, executable, _ = NODES[name]
                supervisor.start(name, [str(executable_path(package, executable)),
                                        '--ros-args', '--params-file', str(params_path)])
        culprit = None
        while not stop_reason:
            executor.spin_once(timeout_sec=0.1)
            exited = supervisor.exited()
            if exited:
                culprit = exited[0]
                break
        if stop_reason:
            code = 130 if stop_reason[0] == 'SIGINT' else 143
        elif culprit.name == 'agent' and culprit.returncode == 0:
            if 'recorder' in supervisor.processes:
                wait_for_closed_episode(supervisor.processes['recorder'], options.practice - 1,
                                        executor, stop_reason)
        else:
            print(f'[session] practice: node {culprit.name} stopped unexpectedly '
                  f'({describe_exit(culprit.returncode)}):\n{culprit.tail()}',
                  file=sys.stderr, flush=True)
            aborted = culprit.name == 'agent' and culprit.returncode == EXIT_OPERATOR_ABORT
            code = EXIT_OPERATOR_ABORT if aborted else 1
    finally:
        supervisor.stop_all(STOP_ORDER)
    done = options.practice if code == 0 else practised()
    print(f'[session] practice done: {done} of {options.practice} episodes'
          if code == 0 else f'[session] practice stopped after {done} of {options.practice} '
                            f'episodes ({describe_exit(code)})', flush=True)
    return code
