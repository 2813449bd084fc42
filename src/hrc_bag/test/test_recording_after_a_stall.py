"""A recorder that was stalled receives an episode's summary before its last states.

After a stall (SIGSTOP, a swapped-out process) each writer retransmits what the recorder
missed in its own order, but the topics do not keep an order between them: the agent's
EpisodeSummary (a quiet topic) came before the sim's last states of the episode, the file
closed on the summary and those states went to the next episode's file. The file now waits
for the state of the summary's last step (at most ``summary_timeout``).
"""

import dataclasses

from hrc_msgs.msg import EpisodeSummary, TaskState
from rosbags.highlevel import AnyReader

from hrc_bag.format import TopicDescription
from hrc_bag.recorder_params import RecorderParams
from hrc_bag.recording import EpisodeRecorder
from hrc_testing.bag_traffic import ManualClock, QOS_PROFILE, RecorderFeeder



def make_recorder(tmp_path, clock, **changes):
    params = dataclasses.replace(RecorderParams(output_dir=str(tmp_path), session_id='s',
                                                summary_timeout=3.0), **changes)
    return EpisodeRecorder(params, lambda topic, type_name: TopicDescription(
        type_name, (QOS_PROFILE,), 'RIHS01_' + '0' * 64), clock=clock)


def state_steps(path):
    """Return (episode, step) of the states in one file, read back by rosbags."""
    with AnyReader([path]) as reader:
        connections = [c for c in reader.connections if c.topic == '/hrc/state']
        states = [reader.deserialize(raw, connection.msgtype)
                  for connection, _, raw in reader.messages(connections=connections)]
    return [(state.episode, state.step) for state in states]


def test_the_last_states_after_the_summary_stay_in_their_episodes_file(tmp_path):
    clock = ManualClock()
    recorder = make_recorder(tmp_path, clock)
    feed = RecorderFeeder(recorder)
    for step in range(3):
        feed.send('/hrc/state', TaskState(episode=0, step=step))
    feed.send('/hrc/episode', EpisodeSummary(episode=0, steps=5))   # before steps 3-5
    clock.now += 0.5
    recorder.tick()
    assert not recorder.closed_files                    # step 5 not here yet: still open
    for step in range(3, 6):
        feed.send('/hrc/state', TaskState(episode=0, step=step, truncated=step == 5))
    recorder.tick()
    assert [info.name for info in recorder.closed_files] == ['s_episode0001.mcap']
    feed.send('/hrc/state', TaskState(episode=1, step=0))
    recorder.close()
    folder = tmp_path / 's'
    assert state_steps(folder / 's_episode0001.mcap') == [(0, step) for step in range(6)]
    assert state_steps(folder / 's_episode0002.mcap') == [(1, 0)]


def test_a_summary_whose_last_state_never_comes_closes_after_the_timeout(tmp_path):
    clock = ManualClock()
    recorder = make_recorder(tmp_path, clock)
    feed = RecorderFeeder(recorder)
    feed.send('/hrc/state', TaskState(episode=0, step=0))
    feed.send('/hrc/episode', EpisodeSummary(episode=0, steps=4))
    clock.now += 2.9
    recorder.tick()
    assert not recorder.closed_files
    clock.now += 0.2
    recorder.tick()
    assert [info.name for info in recorder.closed_files] == ['s_episode0001.mcap']


def test_a_summary_after_its_last_state_closes_the_file_at_once(tmp_path):
    clock = ManualClock()
    recorder = make_recorder(tmp_path, clock)
    feed = RecorderFeeder(recorder)
    for step in range(3):
        feed.send('/hrc/state', TaskState(episode=0, step=step, terminated=step == 2))
    feed.send('/hrc/episode', EpisodeSummary(episode=0, steps=2))
    assert [info.name for info in recorder.closed_files] == ['s_episode0001.mcap']
