"""Each episode's summary says how often both actors reversed; the simulated person is human-like.

A short session of case 5 (the human acts from the first episode) through the in-process
engine with the real PyBullet sim and the simulated person of two profiles at their own rate
(0.02 s slices): every EpisodeSummary carries both actors' reversals per second, and the
simulated person stays under the rate at which people correct (hrc_common.smoothness), which a
model of a person must (Loram et al. 2011).
"""

import math

from hrc_common.session_plan import SessionSettings
from hrc_common.smoothness import chatters
from hrc_engine.engine import EngineConfig, SummariesSession
import pytest


@pytest.mark.parametrize('profile', ['paper', 'novice'])
def test_the_simulated_person_reverses_less_often_than_people_correct(profile):
    session = SummariesSession(EngineConfig(SessionSettings(
        case=5, seed=0, training_episodes=2, evaluation_episodes=1, session_id='reversals',
        record=False, overrides={'sim.episode_duration': 20.0, 'human.profile': profile}),
        checkpoints=False))
    session.run()
    assert len(session.summaries) == 3
    for summary in session.summaries:
        assert math.isfinite(summary['robot_reversals']) and summary['robot_reversals'] >= 0
        assert 0 < summary['human_reversals'] and not chatters(summary['human_reversals']), \
            summary
