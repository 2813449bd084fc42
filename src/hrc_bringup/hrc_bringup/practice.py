"""The practice before a live condition: the person alone on their degree of freedom."""

from dataclasses import replace
import pathlib
import sys
import time

from hrc_common import qos, topics
from hrc_common.contract import DOF_INDEX, Phase
from hrc_common.executables import executable_path
from hrc_common.session_plan import compose, NODES, SessionSettings, write_session_files
from hrc_msgs.msg import SessionStatus, TaskState
from hrc_msgs.srv import ResetEpisode

from hrc_bringup.session_args import person_input
from hrc_bringup.session_progress import Progress
from hrc_bringup.supervisor import describe_exit, Supervisor

# Seconds given to DDS discovery after every practice node is seen, before the sim starts.
DISCOVERY_SETTLE_S = 1.0


def practice_subtask(human_dof: str) -> str:
    """Return the subtask the person holds alone on their degree of freedom."""
    return 'slider' if human_dof == 'translation' else 'pendulum'


def wait_for_closed_episode(recorder, episode: int, executor, stop_reason: list,
                            timeout: float = 30.0) -> bool:
    """Wait until the recorder closed the file of ``episode`` (its log says so).

    Without an agent no EpisodeSummary closes it: the recorder closes it ``summary_timeout``
    after its final state, later when it lags behind; stopping it earlier would lose the
    messages still queued.
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
    the runner starts each of the ``options.practice`` episodes itself (``/hrc/sim/reset``,
    realtime clock) once everything listens, with the agent's ``episode_break`` between them,
    and announces the practice on /hrc/session (strategy ``practice``) so the human node, the
    page and the recorder know the roles. Recorded as the session ``<session-id>-practice``.
    Returns the exit code (0 = every practice episode ran).
    """
    practice = replace(settings, session_id=f'{settings.session_id}-practice', resume_from='')
    parameters = compose(practice, params_dir)
    episode_break = float(parameters.pop('agent').get('episode_break', 3.0))
    parameters['sim'].update(start_on_launch=False, auto_reset=False, max_episodes=0,
                             expected_actors=['human'])
    if person_input(settings, options):
        parameters['human']['on_input_lost'] = ('sim' if options.stand_in == 'sim'
                                                else 'pause')
    run_dir = pathlib.Path(settings.runs_dir) / practice.session_id
    if settings.record:
        parameters['recorder']['session_config'] = str(run_dir / 'session.yaml')
    params_path, _ = write_session_files(practice, parameters, run_dir)
    supervisor = Supervisor(run_dir / 'logs', env)
    human_dof = parameters['human']['dof']
    robot_dof = parameters['sim']['robot_dof']
    node = progress.node
    publisher = node.create_publisher(SessionStatus, topics.SESSION, qos.SESSION_QOS)
    reset = node.create_client(ResetEpisode, topics.RESET_SERVICE)
    finished = []

    def announce(done: int) -> None:
        publisher.publish(SessionStatus(
            session_id=practice.session_id, case_id=settings.case, strategy='practice',
            training_step=0, training_step_count=1, robot_dof=DOF_INDEX[robot_dof],
            human_dof=DOF_INDEX[human_dof], human_involved=True,
            human_subtasks=[practice_subtask(human_dof)], episode=done, total_episodes=done,
            human_involved_episodes=done, phase=int(Phase.TRAINING),
            message=f'practice: episode {min(done + 1, options.practice)} of '
                    f'{options.practice}, the person alone (the robot does not act)'))

    def on_state(state) -> None:
        if (state.truncated or state.terminated) and state.episode not in finished:
            finished.append(state.episode)
            announce(len(finished))

    def spin_until(condition, seconds: float) -> bool:
        deadline = time.monotonic() + seconds
        while not condition():
            if stop_reason or supervisor.exited() or time.monotonic() > deadline:
                return False
            executor.spin_once(timeout_sec=0.1)
        return True

    subscription = node.create_subscription(TaskState, topics.STATE, on_state, qos.STATE_QOS)
    announce(0)
    print(f'[session] practice: {options.practice} episodes of the person alone on the '
          f'{human_dof} (realtime, the robot does not act), recorded as {practice.session_id}',
          flush=True)
    code = 0
    try:
        for name in ('recorder', 'human', 'sim'):
            if name in parameters:
                package, executable, _ = NODES[name]
                supervisor.start(name, [str(executable_path(package, executable)),
                                        '--ros-args', '--params-file', str(params_path)])
        # The first episode starts once everything listens (the runner, the recorder, the
        # human node, the page on the states; the runner, the recorder, the page on the human's
        # answers) and discovery had a moment to match them all.
        pages = 1 if options.display else 0
        ready = spin_until(lambda: (
            reset.service_is_ready() and node.count_publishers(topics.STATE) >= 1
            and node.count_subscribers(topics.STATE) >= 3 + pages
            and node.count_publishers(topics.HUMAN_ACTION) >= 1
            and node.count_subscribers(topics.HUMAN_ACTION) >= 2 + pages), 60.0)
        spin_until(lambda: False, DISCOVERY_SETTLE_S)
        for episode in range(options.practice if ready else 0):
            if episode:
                spin_until(lambda: False, episode_break)  # the person rests
            reset.call_async(ResetEpisode.Request(seed=-1, episode=episode,
                                                  clock_mode='realtime'))
            if not spin_until(lambda: len(finished) > episode,
                              parameters['sim']['episode_duration'] * 3 + 30.0):
                break
        if len(finished) == options.practice and 'recorder' in supervisor.processes:
            wait_for_closed_episode(supervisor.processes['recorder'], options.practice - 1,
                                    executor, stop_reason)
        if stop_reason:
            code = 130 if stop_reason[0] == 'SIGINT' else 143
        elif len(finished) < options.practice:
            exited = supervisor.exited()
            culprit = exited[0] if exited else None
            print('[session] practice: ' + (
                f'node {culprit.name} stopped unexpectedly ({describe_exit(culprit.returncode)})'
                f':\n{culprit.tail()}' if culprit else
                'the practice episodes did not run (see the logs in ' + str(run_dir) + ')'),
                file=sys.stderr, flush=True)
            code = 1
    finally:
        supervisor.stop_all(('human', 'sim', 'recorder'))
        node.destroy_subscription(subscription)
        node.destroy_publisher(publisher)
        node.destroy_client(reset)
    print(f'[session] practice done: {len(finished)} of {options.practice} episodes'
          if code == 0 else f'[session] practice stopped ({describe_exit(code)})', flush=True)
    return code
