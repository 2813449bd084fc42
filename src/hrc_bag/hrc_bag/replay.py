"""What the replay node plays and when (pure, no rclpy).

The recording time of a message is its log time (when the recorder received it). Playback maps
recording time to wall time: the message recorded ``d`` seconds after the start of the bag
(plus ``start_offset``) is published ``d / rate`` seconds after playback started, so relative
timing is kept (scaled by ``rate``). The bag's start is its first message on any topic, so a
topic selection does not shift the timing.
"""

from dataclasses import dataclass
import typing

from hrc_common.contract import NS_PER_S as NANOSECONDS
from hrc_common.params import param

from hrc_bag import bag_reader
from hrc_bag.qos_yaml import duration_ns, load_profiles

ALL_TOPICS = '*'


@dataclass
class ReplayParams:
    """Parameters of the replay node (node ``replay``, params/replay.yaml)."""

    path: str = param('', 'episode file (.mcap) or session folder (with metadata.yaml) to play')
    rate: float = param(1.0, 'playback speed factor (2.0 = twice as fast)', low=0.01,
                        high=1000.0)
    loop: bool = param(False, 'start again at the end, until stopped')
    topics: list = param([ALL_TOPICS], f'topics to play; [{ALL_TOPICS}] = every recorded topic')
    start_offset: float = param(0.0, 'seconds of the recording skipped at its start', low=0.0,
                                high=1.0e9)
    start_delay: float = param(1.0, 'wall seconds between creating the publishers and the '
                               'first message (lets subscribers discover them)', low=0.0,
                               high=600.0)
    wait_for_subscribers: int = param(0, 'after start_delay, wait until every replayed topic '
                                      'has this many subscriptions (0 = do not wait)', low=0,
                                      high=1000)
    clock: bool = param(False, 'publish /clock with the recording time (a recorded /clock is '
                        'then not replayed)')
    clock_rate: float = param(40.0, '/clock publication rate (Hz)', low=1.0, high=1000.0)

    def check(self):
        """Return the reasons why the values are bad."""
        reasons = []
        if not self.path:
            reasons.append('path: give an episode file or a session folder to play')
        else:
            # a missing path, a FIFO or device, an empty or non-MCAP file: each one named
            reasons += [f'path: {problem}' for problem in bag_reader.bag_problems(self.path)]
        if not self.topics:
            reasons.append(f'topics: give topic names or [{ALL_TOPICS}]')
        return reasons

    def selected(self, topic: str) -> bool:
        """Return True when ``topic`` is to be played."""
        return ALL_TOPICS in self.topics or topic in self.topics


class Timeline:
    """Map recording time (ns) to seconds after playback start, and back."""

    def __init__(self, bag_start: int, rate: float, start_offset: float):
        self.first = bag_start + int(round(start_offset * NANOSECONDS))
        self.rate = rate

    def due(self, log_time: int) -> float:
        """Return when (s after playback start) a message of ``log_time`` is published."""
        return (log_time - self.first) / NANOSECONDS / self.rate

    def recording_time(self, elapsed: float) -> int:
        """Return the recording time (ns) that ``elapsed`` wall seconds of playback reach."""
        return self.first + int(elapsed * self.rate * NANOSECONDS)


def bag_start(path) -> typing.Optional[int]:
    """Return the log time of the bag's first message (any topic), or None if it is empty."""
    for file in bag_reader.session_files(path):
        messages = bag_reader.scan_file(file).messages
        if messages:
            return messages[0].log_time
    return None


def playlist(path, params: ReplayParams, skip_topics=()) -> typing.Iterator:
    """Yield the messages to play, file after file, in log-time order, from the offset on."""
    start = bag_start(path)
    if start is None:
        return
    first = start + int(round(params.start_offset * NANOSECONDS))
    for file in bag_reader.session_files(path):
        for message in bag_reader.scan_file(file).messages:
            if message.log_time < first or not params.selected(message.topic):
                continue
            if message.topic in skip_topics:
                continue
            yield message


@dataclass(frozen=True)
class PublisherQos:
    """The QoS to offer for a replayed topic, from the recorded offers (plain values)."""

    reliable: bool
    transient_local: bool
    depth: int
    deadline_ns: int            # 0 = none
    lifespan_ns: int
    liveliness_lease_ns: int


def publisher_qos(channel_metadata: typing.Mapping) -> PublisherQos:
    """Return the QoS to offer: that of the first recorded publisher (rosbag2 does alike).

    Offering the recorded deadline keeps subscribers that request one (the sim's command
    subscriptions) compatible. Unknown policies fall back to reliable, volatile, depth 10.
    """
    try:
        profiles = load_profiles(channel_metadata.get('offered_qos_profiles', ''))
    except ValueError:
        profiles = []
    if not profiles:
        return PublisherQos(True, False, 10, 0, 0, 0)
    profile = profiles[0]
    depth = int(profile.get('depth', 0) or 0)
    return PublisherQos(
        reliable=profile.get('reliability') != 'best_effort',
        transient_local=profile.get('durability') == 'transient_local',
        depth=depth if depth > 0 else 10,
        deadline_ns=duration_ns(profile.get('deadline', {})),
        lifespan_ns=duration_ns(profile.get('lifespan', {})),
        liveliness_lease_ns=duration_ns(profile.get('liveliness_lease_duration', {})))
