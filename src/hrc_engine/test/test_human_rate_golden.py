"""``sim.human_period = control_period`` reproduces the sessions from before human slices.

With the simulated person of that time (``paper_v1``, the ``paper`` profile's numbers before
issue 21 made its perception human-like; ``sim_human.yaml``). The digests were taken at commit
0aecc4c (before the human's own rate existed) with
``golden.session_digest`` and the same configurations: every state, command, human action,
agent step and episode summary of two short sessions (cases 4 and 5: the human acts from the
first episode; a PPO update after the second episode). Any change of those numbers at the old
rate fails here.
"""

import hashlib
import json

from hrc_common.session_plan import SessionSettings
from hrc_testing.sessions import exact_plain
from hrc_engine.engine import EngineConfig, InProcessSession
import pytest

FIELDS = {
    '/hrc/state': ('header', 'episode', 'step', 'slider_position', 'slider_velocity',
                   'pendulum_angle', 'pendulum_angular_velocity', 'ball_position',
                   'ball_velocity', 'applied_force', 'applied_torque',
                   'robot_command_missing', 'human_command_missing', 'terminated',
                   'truncated'),
    '/hrc/robot/cmd_wrench': ('header', 'wrench'),
    '/hrc/human/cmd_wrench': ('header', 'wrench'),
    # (source_detail names the profile: 'paper' then, 'paper_v1' for the same numbers now)
    '/hrc/human/action': ('header', 'episode', 'step', 'command', 'dof', 'source', 'engaged'),
    '/hrc/agent/step': ('header', 'episode', 'step', 'observation_human_action', 'action',
                        'wrench', 'subtask_ids', 'reward_components', 'reward',
                        'value_estimate', 'log_prob', 'deterministic'),
    '/hrc/episode': ('header', 'session_id', 'case_id', 'episode', 'training_step',
                     'human_involved', 'evaluation', 'steps', 'terminated', 'truncated',
                     'episode_return', 'slider_error', 'pendulum_error', 'ball_error',
                     'total_error', 'robot_effort', 'human_effort', 'converged'),
}


class _Capturing(InProcessSession):
    def __init__(self, config):
        super().__init__(config)
        self.captured = []

    def _write(self, topic, message):
        if topic in FIELDS:
            self.captured.append([topic, {name: exact_plain(message[name])
                                          for name in FIELDS[topic]}])


def session_messages(config) -> list:
    """Run the session of ``config`` (an EngineConfig, record False); return its messages."""
    session = _Capturing(config)
    session.run()
    return session.captured


def session_digest(config) -> tuple:
    """Return (SHA-256 hex of the session's messages, count of messages)."""
    captured = session_messages(config)
    text = json.dumps(captured, sort_keys=True, separators=(',', ':'))
    return hashlib.sha256(text.encode()).hexdigest(), len(captured)


BEFORE_HUMAN_SLICES = {
    4: ('2fb285e1f80df3e32c54890e1dc238aa9bc3418131f3751cf45b4a21eb8ceebc', 606),
    5: ('55fb39ea1866b3e427874da535c033664d1c2dc18773c52b7da1a755087885a1', 606),
}


def config(case: int, human_period: float, profile: str = 'paper_v1') -> EngineConfig:
    return EngineConfig(SessionSettings(
        case=case, seed=0, training_episodes=2, evaluation_episodes=1, session_id='golden',
        record=False, overrides={'sim.episode_duration': 8.0, 'agent.horizon': 80,
                                 'sim.human_period': human_period, 'human.profile': profile}),
        checkpoints=False)


@pytest.mark.parametrize('case', sorted(BEFORE_HUMAN_SLICES))
def test_the_old_rate_and_person_reproduce_the_sessions_from_before(case):
    assert session_digest(config(case, 0.2)) == BEFORE_HUMAN_SLICES[case]


def test_the_human_rate_changes_the_session_and_sends_a_wrench_per_slice():
    digest, messages = session_digest(config(5, 0.02))
    assert digest != BEFORE_HUMAN_SLICES[5][0]
    # 3 episodes x 40 steps: 9 more human wrenches per step (one per slice state)
    assert messages - BEFORE_HUMAN_SLICES[5][1] == 3 * 40 * 9
