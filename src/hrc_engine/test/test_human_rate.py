"""The simulated person at its own rate in the in-process engine: one wrench per human slice.

Two short sessions of case 5 (the human acts from the first episode; 2 training episodes and
1 evaluation episode of 8 s, 40 control steps each), once with ``sim.human_period`` equal to
the control period (0.2 s: one slice per period) and once at the default 0.02 s (10 slices).
"""

import collections

from hrc_common.session_plan import SessionSettings
from hrc_engine.engine import EngineConfig, InProcessSession

EPISODES = 3          # 2 training + 1 evaluation
STEPS = 40            # 8 s episodes at the 0.2 s control period


class _Counting(InProcessSession):
    def __init__(self, config):
        super().__init__(config)
        self.counts = collections.Counter()

    def _write(self, topic, message):
        self.counts[topic] += 1


def topic_counts(human_period: float) -> collections.Counter:
    """Return the messages per topic of the session at ``human_period`` (s)."""
    session = _Counting(EngineConfig(SessionSettings(
        case=5, seed=0, training_episodes=2, evaluation_episodes=1, session_id='human-rate',
        record=False, overrides={'sim.episode_duration': 8.0, 'agent.horizon': 80,
                                 'sim.human_period': human_period, 'human.profile': 'paper'}),
        checkpoints=False))
    session.run()
    return session.counts


def test_the_human_rate_sends_a_wrench_per_slice():
    per_period = topic_counts(0.2)
    per_slice = topic_counts(0.02)
    # 9 more human wrenches per step (one per slice state); one HumanAction per step either way
    assert (per_slice['/hrc/human/cmd_wrench'] - per_period['/hrc/human/cmd_wrench']
            == EPISODES * STEPS * 9), (per_period, per_slice)
    assert per_slice['/hrc/human/action'] == per_period['/hrc/human/action'] > 0
