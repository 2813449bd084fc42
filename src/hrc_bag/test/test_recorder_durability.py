"""What a SIGKILL of the recorder can cost, in the recorder's own time (no ROS, no processes).

The node test (test_recorder_node.py) kills a real recorder at moments it cannot time on a
loaded machine, so it kills after a close it has seen; the delays the defaults promise are
checked here, on a fake clock that no load can stretch. (Before: close_grace 0.5 s,
reorder_window 0.5 s and flush_period 1.0 s left a finished episode open for a second, and a
kill lost it; these tests fail with those values.)
"""

import dataclasses

from hrc_msgs.msg import AgentStep, EpisodeSummary, TaskState
import pytest
from rclpy.serialization import serialize_message

from hrc_bag import bag_reader
from hrc_bag.format import RawMessage, TopicDescription
from hrc_bag.recorder_params import RecorderParams
from hrc_bag.boundaries import boundary_event
from hrc_bag.recording import EpisodeRecorder
from hrc_testing.bag_traffic import type_name_of

PROFILE = {'history': 'keep_last', 'depth': 10, 'reliability': 'reliable',
           'durability': 'volatile'}
TICK = 0.01                 # s of fake time between two ticks of the recorder
CLOSED_WITHIN = 0.3         # s after the EpisodeSummary's reception: its file is closed
WRITTEN_WITHIN = 0.35       # s after a message's reception: it is in the open file


class Recorder:
    """An EpisodeRecorder on one fake time (s) for its monotonic clock and its wall clock."""

    def __init__(self, tmp_path, **changes):
        self.now = 1000.0
        params = dataclasses.replace(RecorderParams(output_dir=str(tmp_path), session_id='d'),
                                     **changes)
        self.core = EpisodeRecorder(
            params, lambda topic, type_name: TopicDescription(type_name, (PROFILE,), ''),
            clock=lambda: self.now, wall_clock=lambda: round(self.now * 1e9))
        self.folder = tmp_path / 'd'

    def receive(self, topic, message):
        """Hand over a message received now (the recorder does not lag)."""
        type_name = type_name_of(message)
        stamp = round(self.now * 1e9)
        self.core.record(RawMessage(topic, type_name, serialize_message(message), stamp, stamp),
                         boundary_event(type_name, message))

    def run(self, seconds: float):
        """Let ``seconds`` pass, ticking as the node does."""
        for _ in range(round(seconds / TICK)):
            self.now += TICK
            self.core.tick()

    def closed(self) -> list:
        return [info.name for info in self.core.closed_files]


def send_episode(recorder, episode: int, steps: int, summary: bool = True):
    for step in range(steps):
        recorder.receive('/hrc/state', TaskState(episode=episode, step=step,
                                                 truncated=summary and step == steps - 1))
        recorder.receive('/hrc/agent/step', AgentStep(episode=episode, step=step))
        recorder.run(0.01)
    if summary:
        recorder.receive('/hrc/episode', EpisodeSummary(episode=episode))


def test_with_the_defaults_a_finished_episode_is_closed_soon_after_its_summary(tmp_path):
    recorder = Recorder(tmp_path)
    send_episode(recorder, 0, steps=5)
    recorder.run(CLOSED_WITHIN)
    assert recorder.closed() == ['d_episode0001.mcap']
    assert bag_reader.read_bag_metadata_yaml(recorder.folder)['relative_file_paths'] == [
        'd_episode0001.mcap']
    assert bag_reader.is_complete(recorder.folder / 'd_episode0001.mcap')
    recorder.core.close()


def test_with_the_defaults_the_open_episode_is_on_disk_soon_after_it_was_received(tmp_path):
    recorder = Recorder(tmp_path)
    send_episode(recorder, 0, steps=4, summary=False)   # running when the recorder is killed
    recorder.run(WRITTEN_WITHIN)
    scan = bag_reader.scan_file(recorder.folder / 'd_episode0001.mcap')
    assert not scan.complete and len(scan.messages) == 8
    recorder.core.close()


@pytest.mark.parametrize('changes', [{'close_grace': 0.5}, {'reorder_window': 0.5},
                                     {'flush_period': 1.0}])
def test_the_old_defaults_fail_these_bounds(tmp_path, changes):
    """Each old value alone breaks one of the two bounds above (the bounds have teeth)."""
    recorder = Recorder(tmp_path, **changes)
    send_episode(recorder, 0, steps=4)
    send_episode(recorder, 1, steps=4, summary=False)
    recorder.run(max(CLOSED_WITHIN, WRITTEN_WITHIN))
    open_file = recorder.folder / 'd_episode0002.mcap'
    open_messages = len(bag_reader.scan_file(open_file).messages) if open_file.exists() else 0
    assert recorder.closed() != ['d_episode0001.mcap'] or open_messages < 8
    recorder.core.close()
