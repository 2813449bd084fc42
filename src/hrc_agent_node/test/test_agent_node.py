"""The agent node over DDS, in its own process, driven by a small fake sim in the test process.

The fake sim steps the real physics core (2 s episodes = 10 steps) in lockstep on the robot's
command, serves /hrc/sim/reset, and plays a human that publishes its action for each state
(sometimes before, sometimes after the state, so the agent's wait-for-stamp is exercised).
"""

import copy
import pathlib
import time

import pytest
import yaml

from geometry_msgs.msg import WrenchStamped
from hrc_common.paths import params_dir
from hrc_common import qos, topics
from hrc_msgs.msg import AgentStep, EpisodeSummary, HumanAction, SessionStatus, TaskState
from hrc_msgs.srv import ResetEpisode
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

# 10 control steps per episode; limits unlike the defaults: the agent must scale its wrench
# with what the sim's reset response says, having no values of its own.
PHYSICS = PhysicsParams(episode_duration=2.0, max_force=3.5, max_torque=0.75)
STEPS = PHYSICS.steps_per_episode
AGENT_YAML = pathlib.Path(params_dir()) / 'agent.yaml'


def readers_of(node, *topic_names) -> tuple:
    """Return the sorted node names subscribed to each topic, as the graph shows them now."""
    return tuple(tuple(sorted(info.node_name for info in
                              node.get_subscriptions_info_by_topic(topic)))
                 for topic in topic_names)


def human_command(episode, step):
    """Return the fake human's command for a step (distinct values, to check what is seen)."""
    return round(0.1 * ((episode * 3 + step) % 9) - 0.4, 3)


class FakeSim:
    """Lockstep on the robot's command; publishes the human's action for every state."""

    def __init__(self, context, human_answers=True):
        import rclpy

        self.node = rclpy.create_node('fake_sim', context=context)
        self.sim = SliderPendulumBall(PHYSICS)
        self.human_answers = human_answers
        self.state_pub = self.node.create_publisher(TaskState, topics.STATE, qos.STATE_QOS)
        self.human_pub = self.node.create_publisher(HumanAction, topics.HUMAN_ACTION,
                                                    qos.HUMAN_ACTION_QOS)
        self.node.create_service(ResetEpisode, topics.RESET_SERVICE, self.on_reset)
        self.node.create_subscription(WrenchStamped, topics.ROBOT_CMD_WRENCH, self.on_wrench,
                                      qos.COMMAND_QOS)
        self.sessions, self.episodes, self.steps = [], [], []
        self.node.create_subscription(SessionStatus, topics.SESSION, self.sessions.append,
                                      qos.SESSION_QOS)
        self.node.create_subscription(EpisodeSummary, topics.EPISODE, self.episodes.append,
                                      qos.EPISODE_QOS)
        self.node.create_subscription(AgentStep, topics.AGENT_STEP, self.steps.append,
                                      qos.AGENT_STEP_QOS)
        self.sim_time_ns = 0
        self.episode = None
        self.current = None          # the TaskState waiting for its command
        self.published = []          # every TaskState published
        self.answers = []            # (episode, step) of every command matched to a state
        self.human_action_readers = set()
        self.stale = []              # commands whose stamp matched no waiting state
        self.off_axis = []
        self.resets = []
        self.late_human = []         # human actions to publish after the state

    def on_reset(self, request, response):
        self.resets.append((request.episode, request.seed))
        self.episode = request.episode
        self.publish(self.sim.reset(request.seed))
        response.success = True
        response.message = 'reset'
        response.state = self.current
        response.clock_mode = 'lockstep'
        response.control_period = PHYSICS.control_period
        response.max_force = PHYSICS.max_force
        response.max_torque = PHYSICS.max_torque
        return response

    def on_wrench(self, msg):
        if self.current is None or msg.header.stamp != self.current.header.stamp:
            self.stale.append(msg)
            return
        wrench = msg.wrench
        if (wrench.force.x, wrench.force.y, wrench.torque.x, wrench.torque.y,
                wrench.torque.z) != (0.0,) * 5:
            self.off_axis.append(msg)
        self.answers.append((self.current.episode, self.current.step))
        # readers of the human's action while the agent answers (the agent's, with same_step)
        self.human_action_readers.add(self.human_pub.get_subscription_count())
        self.current = None
        self.publish(self.sim.step(wrench.force.z, 0.0))

    def publish(self, physics_state):
        msg = TaskState()
        self.sim_time_ns += int(PHYSICS.control_period * 1e9)
        msg.header.stamp.sec = self.sim_time_ns // 10**9
        msg.header.stamp.nanosec = self.sim_time_ns % 10**9
        msg.header.frame_id = 'world'
        msg.episode = self.episode
        for name in ('step', 'slider_position', 'slider_velocity', 'pendulum_angle',
                     'pendulum_angular_velocity', 'ball_position', 'ball_velocity',
                     'terminated', 'truncated'):
            setattr(msg, name, getattr(physics_state, name))
        final = physics_state.truncated or physics_state.terminated
        human = HumanAction()
        human.header.stamp = msg.header.stamp
        human.episode, human.step = msg.episode, msg.step
        human.command = human_command(msg.episode, msg.step)
        human.dof = HumanAction.DOF_ROTATION
        human.source = HumanAction.SOURCE_SIMULATED
        human.engaged = True
        early = msg.step % 2 == 0
        if self.human_answers and not final and early:
            self.human_pub.publish(human)
        self.current = None if final else msg
        self.published.append(msg)
        self.state_pub.publish(msg)
        if self.human_answers and not final and not early:
            self.late_human.append((time.monotonic() + 0.05, human))

    def spin(self, executor):
        executor.spin_once(timeout_sec=0.01)
        now = time.monotonic()
        while self.late_human and self.late_human[0][0] <= now:
            self.human_pub.publish(self.late_human.pop(0)[1])


def run_until_exit(fake, process, rclpy_context, timeout):
    from rclpy.executors import SingleThreadedExecutor

    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(fake.node)
    deadline = time.monotonic() + timeout
    while process.process.poll() is None and time.monotonic() < deadline:
        fake.spin(executor)
    for _ in range(50):   # collect what is still in flight
        fake.spin(executor)
    executor.shutdown()
    return process.process.poll()


@pytest.fixture
def easy_tree(tmp_path):
    """Write the repository's tree with tolerances every policy meets (steps advance fast)."""
    with open(pathlib.Path(params_dir()) / 'task_tree.yaml') as stream:
        document = yaml.safe_load(stream)
    for subtask in document['subtasks']:
        subtask['tolerance'] = 100.0
    path = tmp_path / 'easy_tree.yaml'
    path.write_text(yaml.safe_dump(document))
    return path


def test_agent_answers_every_step_and_announces_the_session(start_node, rclpy_context,
                                                            easy_tree, tmp_path):
    fake = FakeSim(rclpy_context)
    agent = start_node('hrc_agent_node', 'agent_node', parameters={
        'case': 1, 'seed': 7, 'session_id': 'dds_test', 'task_tree_file': str(easy_tree),
        'convergence_window': 1, 'max_training_episodes': 10, 'evaluation_episodes': 1,
        'horizon': 16, 'minibatch_size': 8, 'checkpoint_dir': str(tmp_path / 'ckpt'),
        'human_action_source': 'same_step'})  # the fake sim checks the same-step protocol
    code = run_until_exit(fake, agent, rclpy_context, timeout=90)
    fake.node.destroy_node()
    assert code == 0, agent.output

    # Per training step: 1 training episode and the PPO update at its end, 1 judging episode
    # that meets the condition (window 1); then 1 evaluation episode.
    judging, evaluation_episode, joined = (1, 3), 4, 2
    assert [episode for episode, _ in fake.resets] == list(range(5))
    assert len({seed for _, seed in fake.resets}) == 5
    expected = [(episode, step) for episode in range(5) for step in range(STEPS)]
    assert fake.answers == expected, 'every non-final state answered exactly once, in order'
    assert fake.stale == [] and fake.off_axis == []
    assert fake.human_action_readers == {1}, 'same_step: the agent reads /hrc/human/action'

    summaries = fake.episodes
    # A judging episode is no Table II evaluation: evaluation false, counted with training.
    assert [(s.episode, s.training_step, s.human_involved, s.evaluation) for s in summaries] == \
        [(0, 0, False, False), (1, 0, False, False), (2, 1, True, False), (3, 1, True, False),
         (4, 1, True, True)]
    assert all(s.steps == STEPS and s.truncated and s.session_id == 'dds_test'
               for s in summaries)
    assert [s.episode for s in summaries if s.converged] == list(judging)
    assert summaries[0].human_effort == 0.0 and summaries[joined].human_effort > 0.0

    # One AgentStep per step: the observed human action is 0 alone, the human's when joined.
    assert [(m.episode, m.step) for m in fake.steps] == expected
    for message in fake.steps:
        seen = human_command(message.episode, message.step) if message.episode >= joined \
            else 0.0
        assert message.observation_human_action == pytest.approx(seen)
        assert message.reward == pytest.approx(sum(message.reward_components))
        assert message.deterministic == (message.episode in judging + (evaluation_episode,))
        assert -1.0 <= message.action <= 1.0
        assert message.wrench == pytest.approx(message.action * PHYSICS.max_force)
    assert 'from the sim: control period 0.2 s, max_force 3.5 N, max_torque 0.75 N*m' \
        in agent.output
    assert list(fake.steps[0].subtask_ids) == ['slider', 'pendulum']
    assert list(fake.steps[-1].subtask_ids) == ['ball', 'slider', 'pendulum']
    stamps = {(s.episode, s.step): s.header.stamp for s in fake.published}
    assert all(m.header.stamp == stamps[(m.episode, m.step)] for m in fake.steps)

    # Session transitions: alone -> updating -> judging -> human joins -> ... -> done.
    phases = [(m.phase, m.training_step, m.human_involved) for m in fake.sessions]
    training, updating = SessionStatus.PHASE_TRAINING, SessionStatus.PHASE_UPDATING
    evaluation, done = SessionStatus.PHASE_EVALUATION, SessionStatus.PHASE_DONE
    assert phases[0] == (training, 0, False)
    # /hrc/session keeps only the newest announcement (depth 1): the short 'updating' one may be
    # replaced before a busy reader takes it, so the updates are read from the agent's log and
    # the phases that last for episodes from the topic, in order.
    assert 'PPO update 1 (after episode 0)' in agent.output
    assert 'PPO update 2 (after episode 2)' in agent.output
    lasting = [phase for phase in phases if phase[0] != updating]
    assert lasting.index((training, 0, False)) < lasting.index((training, 1, True)) \
        < lasting.index((evaluation, 1, True))
    assert all(phase in ((updating, 0, False), (updating, 1, True)) for phase in phases
               if phase[0] == updating)
    assert phases[-1] == (done, 1, True)
    last = fake.sessions[-1]
    assert (last.total_episodes, last.human_involved_episodes) == (4, 2)
    assert (last.robot_dof, last.human_dof) == (SessionStatus.DOF_TRANSLATION,
                                                SessionStatus.DOF_ROTATION)
    assert last.strategy == 'responsibility_guided' and last.case_id == 1
    assert (tmp_path / 'ckpt' / 'dds_test' / 'final.pt').is_file()
    assert (tmp_path / 'ckpt' / 'dds_test' / 'latest.pt').is_file()


def test_missing_human_action_times_out_and_is_reported(start_node, rclpy_context):
    fake = FakeSim(rclpy_context, human_answers=False)
    agent = start_node('hrc_agent_node', 'agent_node', params_file=AGENT_YAML, parameters={
        'case': 5, 'max_training_episodes': 1, 'evaluation_episodes': 0,
        'human_action_timeout': 0.05, 'checkpoint_dir': '', 'human_action_source': 'same_step'})
    code = run_until_exit(fake, agent, rclpy_context, timeout=60)
    fake.node.destroy_node()
    assert code == 0, agent.output
    assert fake.answers == [(0, step) for step in range(STEPS)]
    assert all(message.observation_human_action == 0.0 for message in fake.steps)
    assert 'no human action for episode 0 step 0 within 0.05 s' in agent.output


@pytest.mark.parametrize('parameters, reason', [
    ({'case': 9}, 'case'),
    ({'preset': 'fancy'}, "unknown reward preset 'fancy'"),
    ({'minibatch_size': 1024}, 'minibatch_size: 1024 exceeds horizon 512'),
    ({'resume_from': '/nonexistent/latest.pt'}, 'does not exist'),
    ({'evaluation_only': True}, 'evaluation_only: needs resume_from'),
])
def test_bad_parameters_exit_2_with_the_reason(start_node, parameters, reason):
    agent = start_node('hrc_agent_node', 'agent_node', parameters=parameters)
    assert agent.wait(timeout=60) == 2, agent.output
    assert reason in agent.output


def test_agent_drives_the_real_sim_node(start_node, rclpy_context):
    """With the sim node (lockstep on the robot alone): every step answered, roles adopted."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    node = rclpy.create_node('observer', context=rclpy_context)
    states, sessions = [], []
    # A reader history deeper than the contract's 10 states: in lockstep the sim publishes an
    # episode's 11 states in a few ms, and this observer takes them only every 50 ms (under load
    # later), so with depth 10 the middleware replaced unread states (seen in a loaded run).
    every_state = copy.copy(qos.STATE_QOS)
    every_state.depth = 1000
    node.create_subscription(TaskState, topics.STATE, states.append, every_state)
    node.create_subscription(SessionStatus, topics.SESSION, sessions.append, qos.SESSION_QOS)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    start_node('hrc_sim_node', 'sim_node', parameters={
        'mode': 'lockstep', 'expected_actors': ['robot'], 'episode_duration': 2.0,
        'lockstep_timeout': 10.0, 'marker_rate': 0.0})
    agent = start_node('hrc_agent_node', 'agent_node', parameters={
        'case': 2, 'seed': 1, 'max_training_episodes': 2, 'evaluation_episodes': 1,
        'horizon': 16, 'minibatch_size': 8, 'checkpoint_dir': '',
        # The first episode waits until the observer's subscription is discovered (under load
        # discovery can take longer than the sim's first states).
        'wait_for_subscribers': ['observer']})
    deadline = time.monotonic() + 90
    readers = set()  # (readers of /hrc/state, of /hrc/human/action) seen while states came
    while agent.process.poll() is None and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
        if states:
            readers.add(readers_of(node, topics.STATE, topics.HUMAN_ACTION))
    for _ in range(20):
        executor.spin_once(timeout_sec=0.02)
    executor.shutdown()
    node.destroy_node()
    assert agent.process.poll() == 0, agent.output
    assert [(s.episode, s.step) for s in states] == \
        [(episode, step) for episode in range(3) for step in range(STEPS + 1)]
    assert not any(s.robot_command_missing for s in states)
    # The sim took the roles from /hrc/session: the robot turns the pendulum, nobody pushes.
    assert any(s.applied_torque != 0.0 for s in states)
    assert all(s.applied_force == 0.0 for s in states)
    assert sessions[-1].phase == SessionStatus.PHASE_DONE
    # human_action_source 'applied' (the default) reads the human's command from the state:
    # the agent does not subscribe to /hrc/human/action (a wake-up per step for nothing)
    assert ('agent', 'observer') in {state for state, _ in readers}, readers
    assert all(actions == () for _, actions in readers), readers


def test_the_agent_runs_the_practice_with_the_real_sim_node(start_node, rclpy_context,
                                                            tmp_path):
    """practice_episodes: the person's episodes alone (realtime), announced, labelled, no robot.

    No human node here: the sim (waiting for no robot) steps on its wall timer; the agent
    answers no state, refuses a pause, and exits 0 after its episodes.
    """
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from std_srvs.srv import Trigger

    from hrc_common.session_control import PAUSE_SERVICE

    node = rclpy.create_node('observer', context=rclpy_context)
    pause = node.create_client(Trigger, PAUSE_SERVICE)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    start_node('hrc_sim_node', 'sim_node', parameters={
        'mode': 'lockstep', 'expected_actors': ['human'], 'episode_duration': 1.0,
        'marker_rate': 0.0, 'human_period': 0.2})
    agent = start_node('hrc_agent_node', 'agent_node', parameters={
        'case': 2, 'session_id': 'p-practice', 'practice_episodes': 2, 'mode': 'realtime',
        'episode_break': 0.2, 'checkpoint_dir': str(tmp_path / 'checkpoints'),
        'wait_for_subscribers': ['observer']})
    # The agent starts its episodes only once 'observer' reads the states and the session:
    # the pause is asked and answered before those readers exist, so the practice cannot end
    # (and the agent exit) before the answer, however slow discovery is.
    answers = []
    deadline = time.monotonic() + 90
    while not (answers and answers[0].done()) and agent.process.poll() is None \
            and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
        if not answers and pause.service_is_ready():
            answers.append(pause.call_async(Trigger.Request()))
    states, sessions, summaries, wrenches, steps = [], [], [], [], []
    node.create_subscription(TaskState, topics.STATE, states.append, qos.STATE_QOS)
    node.create_subscription(SessionStatus, topics.SESSION, sessions.append, qos.SESSION_QOS)
    node.create_subscription(EpisodeSummary, topics.EPISODE, summaries.append, qos.EPISODE_QOS)
    node.create_subscription(WrenchStamped, topics.ROBOT_CMD_WRENCH, wrenches.append,
                             qos.COMMAND_QOS)
    node.create_subscription(AgentStep, topics.AGENT_STEP, steps.append, qos.AGENT_STEP_QOS)
    while agent.process.poll() is None and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
    for _ in range(20):
        executor.spin_once(timeout_sec=0.02)
    executor.shutdown()
    node.destroy_node()
    assert agent.process.poll() == 0, agent.output
    assert answers and answers[0].done() and not answers[0].result().success
    assert 'the practice does not pause' in answers[0].result().message
    # Two realtime episodes of 5 periods each, reset by the agent; nothing from the robot.
    assert [(s.episode, s.step) for s in states] == \
        [(episode, step) for episode in range(2) for step in range(6)]
    assert not wrenches and not steps
    assert [(s.episode, s.kind, s.steps, s.session_id) for s in summaries] == [
        (0, EpisodeSummary.KIND_PRACTICE, 5, 'p-practice'),
        (1, EpisodeSummary.KIND_PRACTICE, 5, 'p-practice')]
    assert {s.strategy for s in sessions} == {'practice'}
    assert sessions[-1].message == ('practice: episode 2 of 2, the person alone (the robot '
                                    'does not act)')
    assert sessions[-1].total_episodes == 2
    assert not (tmp_path / 'checkpoints').exists()     # nothing learned, nothing kept


def test_the_first_episode_waits_until_the_session_readers_have_the_first_announcement():
    """Matched is not enough: every matched reader must have acknowledged the writer's history.

    The session writer keeps one sample (transient local, depth 1); a reader that matched late
    gets the session's first announcement as history, and the first episode's announcement
    would replace it before a slow reader (the recorder, under load) had it: its bag then
    lacked the session's first status (seen in a loaded run of the equivalence tests).
    """
    import types

    from hrc_agent_node.agent_node import AgentNode

    class Reader:
        def __init__(self, node_name):
            self.node_name = node_name

    class SessionWriter:
        acknowledged = False

        def get_subscription_count(self):
            return 2

        def wait_for_all_acked(self, timeout):
            return self.acknowledged

    readers = [Reader('human'), Reader('recorder')]
    logged = []
    node = types.SimpleNamespace(
        params=types.SimpleNamespace(wait_for_subscribers=['human', 'recorder'],
                                     reset_timeout=60.0),
        session_pub=SessionWriter(), named_nodes_since=None, waiting_since=0.0,
        get_subscriptions_info_by_topic=lambda topic: readers,
        get_logger=lambda: types.SimpleNamespace(warning=logged.append))
    node.want_state_readers = lambda now: AgentNode.want_state_readers(node, now)
    wait = AgentNode.missing_subscribers
    assert wait(node, 1.0) is True            # both matched, the history not acknowledged yet
    node.session_pub.acknowledged = True
    assert wait(node, 1.5) is False           # acknowledged: the first episode may start
    assert node.subscribers_seen and not logged
    # and its reset will wait until the sim's state writer matched every reader seen here
    assert (node.state_readers_wanted, node.state_readers_since) == (2, 1.5)


def test_a_reset_the_sim_has_not_started_is_asked_again_and_after_the_grace_without_waiting():
    """The sim says retry while its state writer lacks readers: ask again a tick later.

    After SESSION_MATCH_GRACE_S the reset asks without waiting (a reader that never matches
    must not hold the session).
    """
    import time
    import types

    from hrc_agent_node.agent_node import AgentNode, SESSION_MATCH_GRACE_S, TICK_S
    from hrc_msgs.srv import ResetEpisode

    logged = []
    request = ResetEpisode.Request(episode=0, state_readers=3)
    node = types.SimpleNamespace(reset_request=request, reset_future=object(),
                                 reset_retry_at=None, state_readers_since=time.monotonic(),
                                 get_logger=lambda: types.SimpleNamespace(warning=logged.append))
    waiting = ResetEpisode.Response(success=False, retry=True,
                                    message='not started: 2 of 3 readers of /hrc/state matched')
    done = types.SimpleNamespace(result=lambda: waiting)
    before = time.monotonic()
    AgentNode.on_reset_done(node, done)
    assert node.reset_future is None and node.reset_retry_at >= before + TICK_S
    assert request.state_readers == 3 and not logged
    node.state_readers_since -= SESSION_MATCH_GRACE_S + 1.0
    AgentNode.on_reset_done(node, done)
    assert request.state_readers == 0 and 'starting anyway' in logged[0]
