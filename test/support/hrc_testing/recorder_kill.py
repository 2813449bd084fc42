"""SIGKILL a recorder during synthetic session traffic and compare its bags with what was sent.

The harness of the recorder's crash tests (``src/hrc_bag/test/test_recorder_node.py``) and of
``bench/recorder_sigkill.py``: :func:`kill_trial` kills a recorder node during lockstep-paced
episodes (:class:`hrc_testing.bag_traffic.SyntheticSession`), a chosen time after the recorder
closed one of them, finishes the files it left open and reports what was kept, misplaced or
never delivered.
"""

from dataclasses import dataclass, field
import os
import pathlib
import signal
import threading
import time
import typing

from hrc_common import topics as hrc_topics
from hrc_common.contract import NS_PER_S

from hrc_bag import bag_reader, cdr_peek, format
from hrc_bag.recovery import recover_file
from hrc_testing.bag_traffic import episode_messages, SyntheticSession


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
    # episodes (>= 1) whose file metadata.yaml listed just before the kill
    closed_before_kill: list = field(default_factory=list)


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
               steps: int = 25, step_period: float = 0.01, timeout: float = 120.0) -> KillTrial:
    """SIGKILL a recorder (its process group) during lockstep-paced episodes.

    A first episode (0) is sent and waited for until metadata.yaml lists it, which proves the
    recorder hears every topic; then episodes follow until the kill. The kill comes
    ``kill_after`` s after metadata.yaml listed one of them (an event, not a time: a loaded
    machine may take long to send and record an episode), so at least one finished episode is
    known to be closed and the moment still varies. ``timeout`` (s) bounds each wait for a
    close. Afterwards the files the recorder left open are finished by
    :func:`hrc_bag.recovery.recover_file`, and the bags are compared with what ``session`` sent.
    """
    folder = pathlib.Path(folder)

    def listed():
        return bag_reader.read_bag_metadata_yaml(folder).get('relative_file_paths') or []

    def closed_one():
        return any(_episode_of_file(name) not in (None, 0) for name in listed())

    session.publish_status(0)
    session.publish_episode(0, steps=5, step_period=step_period)
    if not _wait(listed, timeout):
        raise TimeoutError(f'the recorder did not close episode 0 in {folder}')
    killed = threading.Event()
    kill_time, closed_at_kill, late = [], [], []

    def kill():
        if _wait(closed_one, timeout):
            time.sleep(kill_after)      # the moment of the kill, after the close
        else:
            late.append(f'the recorder closed no episode after episode 0 in {timeout} s')
        closed_at_kill.extend(listed())
        kill_time.append(time.time_ns())
        os.killpg(recorder_pid, signal.SIGKILL)
        killed.set()

    killer = threading.Thread(target=kill, daemon=True)
    killer.start()
    summaries = publish_until(session, killed.is_set, steps, step_period, first_episode=1)
    killer.join()
    if late:
        raise TimeoutError(f'{late[0]} ({folder})')
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
                     loss_window(session, totals, kill_ns), max(waiting, default=0) / NS_PER_S,
                     sorted(episode for episode in map(_episode_of_file, closed_at_kill)
                            if episode not in (None, 0)))


def _wait(condition, timeout: float, interval: float = 0.05) -> bool:
    """Poll ``condition()`` until true (True) or ``timeout`` s passed (False)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(interval)
    return True


def _episode_of_file(name: str) -> typing.Optional[int]:
    key = format.episode_file_key(name.rsplit('.', 1)[0])
    return None if key is None else key[0]
