"""A human who sits out a training step sends nothing, and the session's numbers stay the same.

Case 2 (task first): the robot learns alone, then the person joins. While the human is not
involved the sim applies nothing of theirs, so answering every state with a zero HumanAction
and a zero wrench (two of a lockstep step's five messages) carried nothing; now the sim does
not await the human then and the human does not answer. The digests below were taken
at commit 75dedd9 (before the change) with this file's ``digests``: every state, robot command,
agent step and episode summary of the session (``others``), and the human's messages of the
episodes where the human is involved (``involved``). Both must stay the same; what goes is the
human's messages of the robot-alone episodes (``alone``: 60 then, one HumanAction and one wrench
for each of the 30 steps of episodes 0-2, none now).
"""

import hashlib
import json

import pytest

from hrc_common.session_plan import SessionSettings
from hrc_common.testing import easy_task_tree, exact_plain
from hrc_engine.engine import EngineConfig, InProcessSession

HUMAN_TOPICS = ('/hrc/human/action', '/hrc/human/cmd_wrench')
BEFORE = {
    'others': ('bb0c930c66f3bda9481fea5d43782467be7b5c920410231dc23eb9ac8372d94b', 224),
    'involved': ('f081928b9bbeddd7571d2856b959db352b9e5565f2b714b2a078cb668ad3e2b9', 440),
}


class _Capturing(InProcessSession):
    """The engine session, its messages kept with the episode of the newest state."""

    def __init__(self, config):
        super().__init__(config)
        self.captured = []            # (topic, episode, message as JSON text)
        self._state_episode = None

    def _write(self, topic, message):
        if topic == '/hrc/state':
            self._state_episode = message['episode']
        if topic != '/hrc/session':
            self.captured.append((topic, self._state_episode, json.dumps(exact_plain(message),
                                                                   sort_keys=True)))


def digest(items) -> tuple:
    items = list(items)
    text = '\n'.join(f'{topic} {episode} {message}' for topic, episode, message in items)
    return hashlib.sha256(text.encode()).hexdigest(), len(items)


def digests(tree_file: str) -> dict:
    """Run the short case-2 session; return the digests of its parts (see the docstring)."""
    session = _Capturing(EngineConfig(SessionSettings(
        case=2, seed=0, training_episodes=8, evaluation_episodes=1, session_id='alone',
        record=False, overrides={'sim.episode_duration': 2.0, 'agent.horizon': 20,
                                 'agent.minibatch_size': 10, 'agent.convergence_window': 1,
                                 'agent.judging_rule': 'in_a_row',
                                 'agent.task_tree_file': tree_file}),
        checkpoints=False))
    result = session.run()
    involved = {summary['episode'] for summary in result.episodes
                if summary['human_involved']}
    captured = session.captured
    return {
        'others': digest(item for item in captured if item[0] not in HUMAN_TOPICS),
        'involved': digest(item for item in captured
                           if item[0] in HUMAN_TOPICS and item[1] in involved),
        'alone': len([item for item in captured
                      if item[0] in HUMAN_TOPICS and item[1] not in involved]),
        'episodes': [(summary['episode'], summary['human_involved'])
                     for summary in result.episodes],
    }


@pytest.fixture
def easy_tree(tmp_path):
    """Return a task tree file whose tolerances any state meets (the robot-alone step ends)."""
    return easy_task_tree(tmp_path)


def test_a_human_who_sits_out_sends_nothing_and_the_session_is_the_same(easy_tree):
    got = digests(easy_tree)
    alone = [episode for episode, involved in got['episodes'] if not involved]
    assert alone and len(alone) < len(got['episodes']), got['episodes']
    assert got['others'] == BEFORE['others']
    assert got['involved'] == BEFORE['involved']
    assert got['alone'] == 0


