"""A human who sits out a training step sends nothing.

Case 2 (task first): the robot learns alone, then the person joins. While the human is not
involved the sim applies nothing of theirs, so it does not await the human then and the human
does not answer: no HumanAction and no wrench of the human in the robot-alone episodes, one of
each for every step of the episodes where the human is involved.
"""

import hashlib
import json

import pytest

from hrc_common.session_plan import SessionSettings
from hrc_testing.sessions import easy_task_tree, exact_plain
from hrc_engine.engine import EngineConfig, InProcessSession

HUMAN_TOPICS = ('/hrc/human/action', '/hrc/human/cmd_wrench')


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


def digests(tree_file: str, **overrides) -> dict:
    """Run the short case-2 session; return the digests of its parts (see the docstring)."""
    session = _Capturing(EngineConfig(SessionSettings(
        case=2, seed=0, training_episodes=8, evaluation_episodes=1, session_id='alone',
        record=False, overrides={'sim.episode_duration': 2.0, 'agent.horizon': 20,
                                 'agent.minibatch_size': 10, 'agent.convergence_window': 1,
                                 'agent.task_tree_file': tree_file, **overrides}),
        checkpoints=False))
    result = session.run()
    involved = {summary['episode'] for summary in result.episodes
                if summary['human_involved']}
    captured = session.captured
    return {
        'others': digest(item for item in captured if item[0] not in HUMAN_TOPICS),
        'involved': digest(item for item in captured
                           if item[0] in HUMAN_TOPICS and item[1] in involved),
        'all': digest(captured),
        'alone': len([item for item in captured
                      if item[0] in HUMAN_TOPICS and item[1] not in involved]),
        'episodes': [(summary['episode'], summary['human_involved'])
                     for summary in result.episodes],
    }


@pytest.fixture
def easy_tree(tmp_path):
    """Return a task tree file whose tolerances any state meets (the robot-alone step ends)."""
    return easy_task_tree(tmp_path)


def test_a_human_who_sits_out_sends_nothing(easy_tree):
    got = digests(easy_tree)
    alone = [episode for episode, involved in got['episodes'] if not involved]
    assert alone and len(alone) < len(got['episodes']), got['episodes']
    assert got['alone'] == 0
    # the involved episodes (10 steps of 0.2 s each): a HumanAction per step and a wrench per
    # slice of the human's own rate (10 a step)
    involved = len(got['episodes']) - len(alone)
    assert got['involved'][1] == involved * 10 * (1 + 10)
