"""Synthetic hrc session traffic: the messages of a session, from one rclpy node or in-process.

Used by the tests and the recorder benchmark to exercise the recorder, replay and report
without the sim and agent: it produces what the graph publishes during an episode (state, both
commands, human action, agent step each control step; the episode summary at the end; session
status when asked), with seeded values, and keeps every message so that a test can compare a
recording with it exactly. With a ``node`` it publishes them with the contract QoS; with a
``sink`` it hands them to ``sink(topic, message)`` (e.g. straight into an EpisodeRecorder).
"""

import copy
from dataclasses import dataclass, field
import math
import os
import pathlib
import signal
import threading
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

from hrc_bag import bag_reader, cdr_peek
from hrc_bag.format import RawMessage, TopicDescription
from hrc_bag.qos_yaml import profile_to_dict
from hrc_bag.recorder_params import RecorderParams
from hrc_bag.boundaries import boundary_event
from hrc_bag.recording import EpisodeRecorder
from hrc_bag.recovery import recover_file

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
                      start_time_ns: int = 1_700_000_000_000_000_000) -> SyntheticSession:
    """Record a synthetic session straight into an EpisodeRecorder (no DDS), deterministically.

    Log times follow the simulation time (1 ms apart within a step); the recorder's clock is
    advanced past ``close_grace`` after each episode. ``plan``: (training_step, human_involved,
    evaluation) per episode, optionally a fourth item, the summary's ``EpisodeSummary.KIND_*``.
    Returns the SyntheticSession (its ``published`` holds every message).
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


def publish_until(session: SyntheticSession, stop, steps: int = 40,
                  step_period: float = 0.005, first_episode: int = 0) -> dict:
    """Publish lockstep-paced episodes until ``stop()`` is true; return {episode: summary ns}.

    Each episode: a SessionStatus, ``steps`` states (the last one final) with their answers,
    ``step_period`` s apart, then the EpisodeSummary, whose wall-clock time (ns since the
    epoch) just after its publication is returned. The episode running when ``stop()`` turns
    true is left unfinished.
    """
    summaries = {}
    episode = first_episode
    while not stop():
        session.publish_status(episode, human_involved=True)
        if session.publish_episode(episode, steps, human_involved=True,
                                   step_period=step_period, stop=stop) is None:
            break
        summaries[episode] = time.time_ns()
        episode += 1
    return summaries


def loss_window(session: SyntheticSession, recorded_counts: dict, kill_ns: int) -> float:
    """Return how long (s) before ``kill_ns`` the oldest message that was not recorded was sent.

    ``recorded_counts``: {topic: messages of the topic found in the bags}. Over reliable DDS
    what a killed recorder keeps of a topic is a prefix of what was published, so the first
    message missing on a topic is the one after that prefix. 0.0 when nothing sent before the
    kill is missing.
    """
    oldest = kill_ns
    for topic, times in session.publish_times.items():
        count = recorded_counts.get(topic, 0)
        if count < len(times) and times[count] < oldest:
            oldest = times[count]
    return (kill_ns - oldest) / NS_PER_S


@dataclass
class KillTrial:
    """What a SIGKILL of the recorder during a lockstep-paced session left (kill_trial)."""

    folder: pathlib.Path
    kill_ns: int                    # wall clock of the kill (ns since the epoch)
    summaries: dict                 # episode -> wall clock ns just after its summary was sent
    closed: list                    # files metadata.yaml listed at the kill (closed files)
    # closed episode (>= 1) -> topics of which the bags hold a message of the episode in
    # another file (a routing failure; recovery, not loss)
    misplaced: dict
    # closed episode (>= 1) -> topics of which a message of the episode is in no file at all:
    # DDS never delivered it (the contract QoS keeps 1..10 samples per writer)
    undelivered: dict
    loss: float                     # s: kill time - send time of the oldest message lost
    unclosed_after: float           # s: the longest a sent summary waited in vain for its close

    def finished(self, seconds: float) -> list:
        """Return the episodes whose summary was sent more than ``seconds`` before the kill."""
        return sorted(episode for episode, sent in self.summaries.items()
                      if self.kill_ns - sent > seconds * NS_PER_S)


def _recorded_by_episode(folder, prefix: str, stamps: dict) -> tuple:
    """Return ({file name: {episode: {topic: count}}}, {topic: count}) of a session folder."""
    decoder = bag_reader.MessageDecoder()
    by_file, totals = {}, {}
    for path in sorted(pathlib.Path(folder).glob('*.mcap')):
        per_episode = by_file.setdefault(path.name, {})
        for message in bag_reader.scan_file(path).messages:
            topic = message.topic[len(prefix):]
            totals[topic] = totals.get(topic, 0) + 1
            stamp, episode = cdr_peek.peek(message.type_name, message.data)
            if episode is None and message.type_name == 'geometry_msgs/msg/WrenchStamped':
                episode = stamps.get(stamp)
            elif message.type_name.endswith('EpisodeSummary'):
                episode = decoder.decode(message).episode
            if episode is None or message.type_name.endswith('SessionStatus'):
                continue
            counts = per_episode.setdefault(episode, {})
            counts[topic] = counts.get(topic, 0) + 1
    return by_file, totals


def kill_trial(session: SyntheticSession, recorder_pid: int, folder, kill_after: float,
               steps: int = 25, step_period: float = 0.01, timeout: float = 60.0) -> KillTrial:
    """SIGKILL a recorder (its process group) ``kill_after`` s into lockstep-paced episodes.

    A first episode (0) is sent and waited for until metadata.yaml lists it, which proves the
    recorder hears every topic; then episodes follow until the kill. Afterwards the files the
    recorder left open are finished by :func:`hrc_bag.recovery.recover_file`, and the bags
    are compared with what ``session`` sent.
    """
    folder = pathlib.Path(folder)

    def listed():
        return bag_reader.read_bag_metadata_yaml(folder).get('relative_file_paths') or []

    session.publish_status(0)
    session.publish_episode(0, steps=5, step_period=step_period)
    deadline = time.monotonic() + timeout
    while not listed():
        if time.monotonic() > deadline:
            raise TimeoutError(f'the recorder did not close episode 0 in {folder}')
        time.sleep(0.05)
    killed = threading.Event()
    kill_time = []

    def kill():
        kill_time.append(time.time_ns())
        os.killpg(recorder_pid, signal.SIGKILL)
        killed.set()

    timer = threading.Timer(kill_after, kill)
    timer.start()
    summaries = publish_until(session, killed.is_set, steps, step_period, first_episode=1)
    timer.join()
    kill_ns = kill_time[0]
    closed = listed()
    for path in sorted(folder.glob('*.mcap')):
        if path.name not in closed:     # left open by the killed recorder
            recover_file(path)
    stamps = {state.header.stamp.sec * NS_PER_S + state.header.stamp.nanosec:
              state.episode for state in session.published.by_topic.get(hrc_topics.STATE, [])}
    by_file, totals = _recorded_by_episode(folder, session.prefix, stamps)
    anywhere = {}
    for per_episode in by_file.values():
        for episode, counts in per_episode.items():
            for topic, count in counts.items():
                anywhere.setdefault(episode, {})
                anywhere[episode][topic] = anywhere[episode].get(topic, 0) + count
    expected = episode_messages(session.published)
    misplaced, undelivered = {}, {}
    for name in closed:
        episode = _episode_of_file(name)
        if episode not in summaries:            # the warm-up episode, the end file
            continue
        own = by_file.get(name, {}).get(episode, {})
        for topic, count in expected[episode].items():
            if own.get(topic, 0) < anywhere.get(episode, {}).get(topic, 0):
                misplaced.setdefault(episode, []).append(topic)
            if anywhere.get(episode, {}).get(topic, 0) < count:
                undelivered.setdefault(episode, []).append(topic)
    closed_episodes = {_episode_of_file(name) for name in closed}
    waiting = [kill_ns - sent for episode, sent in summaries.items()
               if episode not in closed_episodes]
    return KillTrial(folder, kill_ns, summaries, closed, misplaced, undelivered,
                     loss_window(session, totals, kill_ns), max(waiting, default=0) / NS_PER_S)


def _episode_of_file(name: str) -> typing.Optional[int]:
    stem = name.rsplit('.', 1)[0]
    number = stem.rsplit('_ep', 1)[-1] if '_ep' in stem else ''
    return int(number) if number.isdigit() else None
