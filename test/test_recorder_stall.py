"""A recorder stopped mid-session: lockstep waits for it, and the bags miss nothing.

A recorder stopped (SIGSTOP) for some seconds in a lockstep session missed whole episodes
(the writers' keep-last histories overwrote what it had not received) and the runner exited 0.
The sim now publishes no state more than a window ahead of the recorder's acknowledgement
(hrc_sim_node.recorder_gate): the test waits for the sim to say it waits, lets the recorder go
on, and reads every episode's file back with rosbags.
"""

import os
import pathlib
import signal
import time

import pytest
from rosbags.highlevel import AnyReader

from hrc_testing.nodes import node_pid, wait_for
from hrc_testing.sessions import SessionRunner

EPISODES = 8


def states_per_episode(folder: pathlib.Path) -> dict:
    """Return {episode file name: (the steps of its states, whether the last ends it)}."""
    found = {}
    for path in sorted(folder.glob('*_episode*.mcap')):
        with AnyReader([path]) as reader:
            connections = [c for c in reader.connections if c.topic == '/hrc/state']
            states = [reader.deserialize(raw, connection.msgtype)
                      for connection, _, raw in reader.messages(connections=connections)]
        found[path.name] = ([state.step for state in states], bool(states) and bool(
            states[-1].terminated or states[-1].truncated))
    return found


@pytest.mark.slow
def test_a_stalled_recorder_holds_lockstep_and_misses_nothing(tmp_path, ros_domain_id):
    session = SessionRunner(tmp_path, ros_domain_id, 'stall', '--episodes', str(EPISODES),
                            '--eval-episodes', '1')
    output = session.output

    def sim_says(words):
        return words in session.node_log('sim')

    try:
        first = tmp_path / 'bags' / 'stall' / 'stall_episode0001.mcap'
        pid = 0

        def started():
            nonlocal pid
            pid = node_pid('recorder_node', ros_domain_id)
            return first.exists() and pid

        assert wait_for(started, 120), output()
        assert pid > 0 and session.process.poll() is None, output()
        os.kill(pid, signal.SIGSTOP)
        try:    # the sim says it waits (after 5 s of waiting), then the recorder goes on
            assert wait_for(lambda: sim_says('waiting for the recorder'), 120), output()
        finally:
            os.kill(pid, signal.SIGCONT)
        assert wait_for(lambda: sim_says('the recorder caught up'), 120), output()
        assert session.process.wait(timeout=300) == 0, output()
    finally:
        session.stop()
    printed = output()
    assert 'the recorder missed' not in printed, printed
    # the states retransmitted after the stall come after the agent's summary of their
    # episode: its file waits for them (hrc_bag.recording) instead of closing on the summary
    recorder_log = session.node_log('recorder')
    # (a /joint_states message stamped with an episode's last state may come after its
    # summary and go to the next file: not a state, and said in the log)
    assert '(/hrc/state) arrived after its file closed' not in recorder_log, recorder_log[-4000:]
    found = states_per_episode(session.bags())
    # every episode of the session (the training ones and the evaluation) has a whole file:
    # its initial state, one per step with none left out, and a last one that ends it
    assert len(found) >= EPISODES + 1, (sorted(found), printed)
    for name, (steps, ended) in found.items():
        assert ended and len(steps) >= 2 and steps == list(range(len(steps))), (name, steps)


# s: how long the realtime test stops the recorder (a stimulus, not a measure: nothing is
# asserted about time). A realtime sim never waits (a person acts); the writers' histories
# (STREAM_WRITER_DEPTH) hold what 8 s of a realtime episode publishes, so nothing is lost.
REALTIME_STALL_S = 8.0


@pytest.mark.slow
def test_a_recorder_stopped_for_8_s_in_realtime_misses_nothing(tmp_path, ros_domain_id):
    session = SessionRunner(tmp_path, ros_domain_id, 'stall', '--case', '4', '--mode',
                            'realtime', '--episodes', '1', '--eval-episodes', '1', '--set',
                            'sim.episode_duration=12.0', '--set', 'agent.episode_break=0.5')
    output = session.output
    try:     # case 4: the person acts from the first episode, realtime throughout
        assert wait_for(lambda: 'episode 0 started' in session.node_log('sim')
                        and node_pid('recorder_node', ros_domain_id), 120), output()
        pid = node_pid('recorder_node', ros_domain_id)
        os.kill(pid, signal.SIGSTOP)
        try:
            time.sleep(REALTIME_STALL_S)
        finally:
            os.kill(pid, signal.SIGCONT)
        assert session.process.wait(timeout=300) == 0, output()
    finally:
        session.stop()
    printed = output()
    assert 'the recorder missed' not in printed, printed
    found = states_per_episode(session.bags())
    assert len(found) >= 2, (sorted(found), printed)
    for name, (steps, ended) in found.items():
        assert ended and len(steps) >= 2 and steps == list(range(len(steps))), (name, steps)
