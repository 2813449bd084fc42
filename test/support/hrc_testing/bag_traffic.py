"""Synthetic hrc session traffic: the messages of a session, from one rclpy node or in-process.

Used by the tests and the recorder benchmarks to exercise the recorder, replay and report
without the sim and agent: it produces what the graph publishes during an episode (state, both
commands, human action, agent step each control step; the episode summary at the end; session
status when asked), with seeded values, and keeps every message so that a test can compare a
recording with it exactly. With a ``node`` it publishes them with the contract QoS; with a
``sink`` it hands them to ``sink(topic, message)`` (e.g. straight into an EpisodeRecorder).
"""

import copy
from dataclasses import dataclass, field
import math
import time
import typing

from geometry_msgs.msg import WrenchStamped
from hrc_common import qos as hrc_qos
from hrc_common import topics as hrc_topics
from hrc_common.contract import episode_kind, EpisodeKind, NS_PER_S
from hrc_msgs.msg import AgentStep, EpisodeSummary, HumanAction, SessionStatus, TaskState
import numpy
from rclpy.node import Node
from rclpy.serialization import serialize_message

from hrc_bag.format import RawMessage, TopicDescription
from hrc_bag.qos_yaml import profile_to_dict
from hrc_bag.recorder_params import RecorderParams
from hrc_bag.boundaries import boundary_event
from hrc_bag.recording import EpisodeRecorder

CONTROL_PERIOD_NS = 200_000_000    # simulation time per control step (0.2 s)

# topic -> (type, QoS its publisher offers): the contract's (hrc_common.qos_table)
MESSAGE_CLASSES = {
    hrc_topics.STATE: TaskState,
    hrc_topics.ROBOT_CMD_WRENCH: WrenchStamped,
    hrc_topics.HUMAN_CMD_WRENCH: WrenchStamped,
    hrc_topics.HUMAN_ACTION: HumanAction,
    hrc_topics.SESSION: SessionStatus,
    hrc_topics.EPISODE: EpisodeSummary,
    hrc_topics.AGENT_STEP: AgentStep,
}
TOPICS = {topic: (message_class, hrc_qos.OF_TOPIC[topic])
          for topic, message_class in MESSAGE_CLASSES.items()}


@dataclass
class Published:
    """Every message published, per topic (the name without prefix), in order."""

    by_topic: dict = field(default_factory=dict)

    def add(self, topic: str, message) -> None:
        """Remember ``message`` as published on ``topic``."""
        self.by_topic.setdefault(topic, []).append(message)

    def count(self, topic: str = None) -> int:
        """Return how many messages were published (on ``topic``, or in all)."""
        if topic is not None:
            return len(self.by_topic.get(topic, []))
        return sum(len(messages) for messages in self.by_topic.values())



class ManualClock:
    """A monotonic clock a test sets by hand (``clock.now = 2.5``), for an EpisodeRecorder."""

    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


# A recorded topic's offered QoS as rosbag2 writes it (every field, so rosbags reads it).
QOS_PROFILE = {'history': 'keep_last', 'depth': 10, 'reliability': 'reliable',
               'durability': 'volatile', 'deadline': {'sec': 1, 'nsec': 0},
               'lifespan': {'sec': 9223372036, 'nsec': 854775807}, 'liveliness': 'automatic',
               'liveliness_lease_duration': {'sec': 9223372036, 'nsec': 854775807},
               'avoid_ros_namespace_conventions': False}


class RecorderFeeder:
    """Feed messages into an EpisodeRecorder as the node would, with increasing log times."""

    def __init__(self, recorder):
        self.recorder = recorder
        self.log_time = 1_000_000_000

    def send(self, topic, message):
        self.log_time += 1_000_000
        type_name = type_name_of(message)
        self.recorder.record(RawMessage(topic, type_name, serialize_message(message),
                                        self.log_time, self.log_time - 500),
                             boundary_event(type_name, message))


def type_name_of(message) -> str:
    """Return ``pkg/msg/Type`` of a ROS message object."""
    return f'{type(message).__module__.split(".")[0]}/msg/{type(message).__name__}'


class SyntheticSession:
    """Produce a session's traffic through ``node`` publishers and/or a ``sink`` callable."""

    def __init__(self, node: typing.Optional[Node] = None, session_id: str = 'synthetic',
                 case_id: int = 1, strategy: str = 'responsibility_guided', seed: int = 0,
                 robot_dof: int = 0, sink: typing.Optional[typing.Callable] = None,
                 prefix: str = '', history_depth: int = 0):
        # history_depth > 0: each publisher keeps that many samples instead of the contract's
        # 1..10, so a subscriber that lags (a loaded machine) cannot miss any
        self.node = node
        self.sink = sink
        self.prefix = prefix            # publish on <prefix>/hrc/... (tests isolate themselves)
        self.session_id = session_id
        self.case_id = case_id
        self.strategy = strategy
        self.robot_dof = robot_dof
        self.rng = numpy.random.default_rng(seed)
        self.published = Published()
        self.sim_time_ns = 0          # simulation time (ns): integer, so stamps are exact
        self.total_episodes = 0
        self.human_involved_episodes = 0
        self.publishers = {}
        self.publish_times = {}       # topic -> [wall clock ns of each publication]
        # episode -> (steps whose state says the robot's command was missing, the human's)
        self.missing = {}
        if node is not None:
            for topic, (message_type, qos) in TOPICS.items():
                if history_depth:
                    qos = copy.copy(qos)
                    qos.depth = max(qos.depth, history_depth)
                self.publishers[topic] = node.create_publisher(message_type, prefix + topic,
                                                               qos)

    def wait_for_subscribers(self, count: int = 1, timeout: float = 60.0, topics=None,
                             settle: float = 1.0) -> bool:
        """Wait until every publisher (of ``topics``) is matched by ``count`` subscriptions.

        A publisher sees a subscription before that subscription has matched the publisher
        (discovery runs both ways), and samples sent in between are dropped: ``settle``
        seconds are waited on top.
        """
        publishers = [self.publishers[topic] for topic in (topics or self.publishers)]
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if all(publisher.get_subscription_count() >= count for publisher in publishers):
                time.sleep(settle)
                return True
            time.sleep(0.05)
        return False

    def _publish(self, topic: str, message) -> None:
        if self.publishers:
            self.publishers[topic].publish(message)
            self.publish_times.setdefault(topic, []).append(time.time_ns())
        if self.sink is not None:
            self.sink(topic, message)
        self.published.add(topic, message)

    def _stamp(self, message) -> None:
        message.header.stamp.sec, message.header.stamp.nanosec = divmod(self.sim_time_ns, NS_PER_S)

    def publish_status(self, episode: int, phase: int = SessionStatus.PHASE_TRAINING,
                       training_step: int = 0, human_involved: bool = False) -> SessionStatus:
        """Publish a SessionStatus describing the session now."""
        status = SessionStatus()
        self._stamp(status)
        status.session_id = self.session_id
        status.case_id = self.case_id
        status.strategy = self.strategy
        status.training_step = training_step
        status.training_step_count = 2
        status.robot_dof = self.robot_dof
        status.human_dof = 1 - self.robot_dof
        status.human_involved = human_involved
        status.robot_subtasks = ['slider', 'pendulum'] + (['ball'] if training_step else [])
        status.human_subtasks = ['pendulum'] if human_involved else []
        status.episode = episode
        status.total_episodes = self.total_episodes
        status.human_involved_episodes = self.human_involved_episodes
        status.phase = phase
        status.message = f'episode {episode}'
        self._publish(hrc_topics.SESSION, status)
        return status

    def publish_episode(self, episode: int, steps: int = 10, training_step: int = 0,
                        human_involved: bool = False, evaluation: bool = False,
                        step_period: float = 0.0, final: bool = True,
                        stop: typing.Optional[typing.Callable] = None,
                        kind: typing.Optional[int] = None) -> EpisodeSummary:
        """Publish the traffic of one episode of ``steps`` states (the last one final).

        ``kind``: the summary's ``EpisodeSummary.KIND_*`` (None: evaluation or training, from
        ``evaluation``; KIND_UNKNOWN writes a summary as bags before the field read).

        With ``final`` false the episode stops after ``steps`` non-final states (as if the
        graph died); so it does, unfinished, as soon as ``stop()`` is true. Returns the
        EpisodeSummary published (None when not final).
        """
        robot_actions, human_actions = [], []
        errors = numpy.zeros(3)
        for step in range(steps):
            if stop is not None and stop():
                return None
            is_final = final and step == steps - 1
            state = TaskState()
            self._stamp(state)
            state.header.frame_id = 'world'
            state.episode = episode
            state.step = step
            values = self.rng.uniform(-1.0, 1.0, size=6)
            state.slider_position = 0.1 * values[0]
            state.slider_velocity = values[1]
            state.pendulum_angle = 0.5 * values[2]
            state.pendulum_angular_velocity = values[3]
            state.ball_position = 0.25 * values[4]
            state.ball_velocity = values[5]
            state.truncated = is_final
            robot_missing, human_missing = self.missing.get(episode, ((), ()))
            state.robot_command_missing = step in robot_missing
            state.human_command_missing = step in human_missing
            errors += numpy.abs([state.slider_position, state.pendulum_angle,
                                 state.ball_position])
            self._publish(hrc_topics.STATE, state)
            if not is_final:
                robot_action, human_action = (float(value)
                                              for value in self.rng.uniform(-1, 1, size=2))
                if not human_involved:
                    human_action = 0.0
                robot_actions.append(robot_action)
                human_actions.append(human_action)
                self._publish_answers(state, robot_action, human_action, human_involved,
                                      evaluation, training_step)
            self.sim_time_ns += CONTROL_PERIOD_NS
            if step_period:
                time.sleep(step_period)
        if not final:
            return None
        summary = EpisodeSummary()
        self._stamp(summary)
        summary.session_id = self.session_id
        summary.case_id = self.case_id
        summary.episode = episode
        summary.training_step = training_step
        summary.human_involved = human_involved
        summary.evaluation = evaluation
        summary.kind = int(episode_kind(kind, evaluation=evaluation)) if kind is None else kind
        summary.steps = steps
        summary.truncated = True
        summary.episode_return = float(-errors.sum())
        summary.slider_error, summary.pendulum_error, summary.ball_error = (
            float(value) for value in errors / steps)
        summary.total_error = float(errors.sum() / steps)
        summary.robot_effort = float(numpy.var(robot_actions)) if robot_actions else 0.0
        summary.human_effort = float(numpy.var(human_actions)) if human_actions else 0.0
        self._publish(hrc_topics.EPISODE, summary)
        if episode_kind(summary.kind, evaluation=evaluation) in (EpisodeKind.TRAINING,
                                                                 EpisodeKind.JUDGING):
            self.total_episodes += 1
            self.human_involved_episodes += int(human_involved)
        return summary

    def _publish_answers(self, state, robot_action, human_action, human_involved, evaluation,
                         training_step) -> None:
        robot_dof, human_dof = self.robot_dof, 1 - self.robot_dof
        for topic, dof, action in ((hrc_topics.ROBOT_CMD_WRENCH, robot_dof, robot_action),
                                   (hrc_topics.HUMAN_CMD_WRENCH, human_dof, human_action)):
            wrench = WrenchStamped()
            wrench.header = state.header
            if dof == 0:
                wrench.wrench.force.z = 10.0 * action
            else:
                wrench.wrench.torque.x = 2.0 * action
            self._publish(topic, wrench)
        action = HumanAction()
        action.header = state.header
        action.episode = state.episode
        action.step = state.step
        action.command = human_action
        action.dof = human_dof
        action.source = HumanAction.SOURCE_SIMULATED
        action.source_detail = 'synthetic'
        action.engaged = human_involved
        self._publish(hrc_topics.HUMAN_ACTION, action)
        agent = AgentStep()
        agent.header = state.header
        agent.episode = state.episode
        agent.step = state.step
        agent.observation_human_action = human_action
        agent.action = robot_action
        agent.wrench = 10.0 * robot_action
        agent.subtask_ids = ['slider', 'pendulum'] + (['ball'] if training_step else [])
        agent.reward_components = [math.exp(-abs(state.slider_position)),
                                   math.exp(-abs(state.pendulum_angle))] + (
            [math.exp(-abs(state.ball_position))] if training_step else [])
        agent.reward = float(sum(agent.reward_components))
        agent.value_estimate = 0.0
        agent.log_prob = -1.0
        agent.deterministic = evaluation
        self._publish(hrc_topics.AGENT_STEP, agent)


def strategy_plan(strategy: str, first: int, second: int, evaluation: int) -> list:
    """Return [(training_step, human_involved, evaluation), ...] of a session of ``strategy``.

    responsibility_guided: ``first`` episodes without the human, then ``second`` with him;
    level_guided: both steps with the human; learn_together: one step (``first + second``
    episodes) with the human. Then ``evaluation`` evaluation episodes with the human.
    """
    if strategy == 'responsibility_guided':
        training = [(0, False)] * first + [(1, True)] * second
    elif strategy == 'level_guided':
        training = [(0, True)] * first + [(1, True)] * second
    elif strategy == 'learn_together':
        training = [(0, True)] * (first + second)
    else:
        raise ValueError(f'unknown strategy {strategy!r}')
    last_step = training[-1][0] if training else 0
    return ([(step, human, False) for step, human in training]
            + [(last_step, True, True)] * evaluation)


def record_in_process(output_dir, session_id: str, case_id: int, strategy: str, seed: int,
                      plan: list, steps: int = 10, session_config: typing.Optional[dict] = None,
                      start_time_ns: int = 1_700_000_000_000_000_000,
                      missing: typing.Optional[dict] = None) -> SyntheticSession:
    """Record a synthetic session straight into an EpisodeRecorder (no DDS), deterministically.

    Log times follow the simulation time (1 ms apart within a step); the recorder's clock is
    advanced past ``close_grace`` after each episode. ``plan``: (training_step, human_involved,
    evaluation) per episode, optionally a fourth item, the summary's ``EpisodeSummary.KIND_*``.
    ``missing``: {episode: (steps without the robot's command, steps without the human's)},
    set on those states as the sim sets them. Returns the SyntheticSession (its ``published``
    holds every message).
    """
    clock = [0.0]
    params = RecorderParams(output_dir=str(output_dir), session_id=session_id)
    counter = [0]

    def describe(topic, type_name):
        return TopicDescription(type_name, (profile_to_dict(TOPICS[topic][1]),), '')

    recorder = EpisodeRecorder(params, describe, session_config=session_config or {
        'session_id': session_id, 'case': case_id, 'strategy': strategy,
        'roles': {'robot': 'translation' if case_id % 2 else 'rotation',
                  'human': 'rotation' if case_id % 2 else 'translation'},
        'seeds': {'session': seed}}, clock=lambda: clock[0])
    session = None

    def sink(topic, message):
        counter[0] += 1
        log_time = start_time_ns + session.sim_time_ns + counter[0] * 1000
        type_name = type_name_of(message)
        recorder.record(RawMessage(topic, type_name, serialize_message(message), log_time,
                                   log_time, counter[0]),
                        boundary_event(type_name, message))

    robot_dof = 0 if case_id % 2 else 1
    session = SyntheticSession(None, session_id, case_id, strategy, seed, robot_dof, sink)
    session.missing = dict(missing or {})
    for episode, entry in enumerate(plan):
        training_step, human_involved, evaluation = entry[:3]
        kind = entry[3] if len(entry) > 3 else None     # EpisodeSummary.KIND_*, None: inferred
        phase = SessionStatus.PHASE_EVALUATION if evaluation else SessionStatus.PHASE_TRAINING
        session.publish_status(episode, phase, training_step, human_involved)
        session.publish_episode(episode, steps, training_step, human_involved, evaluation,
                                kind=kind)
        clock[0] += params.close_grace + 0.1
        recorder.tick()
    session.publish_status(len(plan), SessionStatus.PHASE_DONE)
    recorder.close()
    return session


def episode_messages(published: Published) -> dict:
    """Return {episode: {topic: count}} of the messages that belong to an episode.

    TaskState, HumanAction, AgentStep and EpisodeSummary name their episode; a command belongs
    to the episode of the state whose stamp it carries; SessionStatus belongs to none.
    """
    stamps = {}
    for state in published.by_topic.get(hrc_topics.STATE, []):
        stamps[(state.header.stamp.sec, state.header.stamp.nanosec)] = state.episode
    counts = {}
    for topic, messages in published.by_topic.items():
        for message in messages:
            episode = getattr(message, 'episode', None)
            if isinstance(message, WrenchStamped):
                episode = stamps.get((message.header.stamp.sec, message.header.stamp.nanosec))
            if episode is None or isinstance(message, SessionStatus):
                continue
            per_topic = counts.setdefault(int(episode), {})
            per_topic[topic] = per_topic.get(topic, 0) + 1
    return counts
