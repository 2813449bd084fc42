"""A frozen actor in a lockstep session: its late commands are marked, and the episode so.

The human node (while the person is involved) or the agent stopped (SIGSTOP) leaves the sim
without their commands (each applied as zero after lockstep_timeout). Such an episode must not
count as a normal one: its EpisodeSummary says how many periods went without a command (the
agent judges again or runs the evaluation again), and the report names it.
"""

import os
import pathlib
import signal

import pytest
from rosbags.highlevel import AnyReader

from hrc_testing.nodes import node_pid, wait_for
from hrc_testing.sessions import SessionRunner


def missing_and_marked(folder: pathlib.Path, actor: str) -> dict:
    """Return {episode: (states without the actor's command, summary's commands_missing)}."""
    found = {}
    for path in sorted(folder.glob('*_episode*.mcap')):
        with AnyReader([path]) as reader:
            wanted = [c for c in reader.connections if c.topic in ('/hrc/state', '/hrc/episode')]
            missing, marked, episode = 0, None, None
            for connection, _, raw in reader.messages(connections=wanted):
                message = reader.deserialize(raw, connection.msgtype)
                if connection.topic == '/hrc/state':
                    missing += bool(getattr(message, f'{actor}_command_missing'))
                    episode = message.episode
                else:
                    marked = int(message.commands_missing)
        found[episode] = (missing, marked)
    return found


# (stopped node, its actor, the sim's words once it may be stopped, the sim's words of a
# missing command, how many of them (one per 2 s at most: 8 are >= 15 s, 4 >= 8 s), options)
FREEZES = {
    'lockstep human': ('human_node', 'human', 'human involved: True', 'no command from human',
                       8, ['--episodes', '12']),
    'lockstep agent': ('agent_node', 'robot', 'episode 2 started', 'no command from robot', 8,
                       ['--episodes', '12']),
    # realtime from the person's first episode on (the robot trains alone in lockstep)
    'realtime agent': ('agent_node', 'robot', 'clock mode switched to realtime',
                       'no fresh command from robot', 4,
                       ['--episodes', '12', '--mode', 'realtime', '--set',
                        'sim.episode_duration=16']),
}


@pytest.mark.slow
@pytest.mark.parametrize('freeze', FREEZES)
def test_a_frozen_actor_leaves_no_unmarked_episode(tmp_path, ros_domain_id, freeze):
    executable, actor, involved, words, warnings, options = FREEZES[freeze]
    session = SessionRunner(tmp_path, ros_domain_id, 'frozen', '--eval-episodes', '1', *options)
    output = session.output
    try:
        assert wait_for(lambda: involved in session.node_log('sim'), 180), output()
        pid = node_pid(executable, ros_domain_id)
        assert pid > 0, output()
        os.kill(pid, signal.SIGSTOP)
        try:
            assert wait_for(lambda: session.node_log('sim').count(words) >= warnings, 120), \
                output()
        finally:
            os.kill(pid, signal.SIGCONT)
        assert session.process.wait(timeout=300) == 0, output()
    finally:
        session.stop()
    found = missing_and_marked(session.bags(), actor)
    late = {episode: counts for episode, counts in found.items() if counts[0]}
    assert late, found
    for episode, (missing, marked) in late.items():
        assert marked is not None and marked >= missing, (episode, found)
    printed = output()
    assert 'not a normal episode' in printed, printed
