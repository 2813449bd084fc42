"""``sim.human_period = control_period`` reproduces the sessions from before human slices.

The digests were taken at commit 0aecc4c (before the human's own rate existed) with
``golden.session_digest`` and the same configurations: every state, command, human action,
agent step and episode summary of two short sessions (cases 4 and 5: the human acts from the
first episode; a PPO update after the second episode). Any change of those numbers at the old
rate fails here.
"""

import hashlib
import json

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
    '/hrc/human/action': ('header', 'episode', 'step', 'command', 'dof', 'source',
                          'source_detail', 'engaged'),
    '/hrc/agent/step': ('header', 'episode', 'step', 'observation_human_action', 'action',
                        'wrench', 'subtask_ids', 'reward_components', 'reward',
                        'value_estimate', 'log_prob', 'deterministic'),
    '/hrc/episode': ('header', 'session_id', 'case_id', 'episode', 'training_step',
                     'human_involved', 'evaluation', 'steps', 'terminated', 'truncated',
                     'episode_return', 'slider_error', 'pendulum_error', 'ball_error',
                     'total_error', 'robot_effort', 'human_effort', 'converged'),
}


def plain(value):
    """Return ``value`` as JSON-able plain values (floats as their repr)."""
    if isinstance(value, dict):
        return {key: plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(item) for item in value]
    if isinstance(value, bool) or value is None or isinstance(value, (int, str)):
        return value
    if isinstance(value, float):
        return repr(value)
    if hasattr(value, '__dict__'):
        return plain(vars(value))
    return repr(float(value))


class _Capturing(InProcessSession):
    def __init__(self, config):
        super().__init__(config)
        self.captured = []

    def _write(self, topic, message):
        if topic in FIELDS:
            self.captured.append([topic, {name: plain(message[name])
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
    4: ('5d1c5390df3b0c3174dec475f236a6dbfa1b32d2127fd5c14f0b68256fa5396d', 606),
    5: ('be6cc2990430a189eebf3f8fa24a9a670fbd97ca17faf5dd5c9cbf1242f05cad', 606),
}


def config(case: int, human_period: float) -> EngineConfig:
    return EngineConfig(case=case, seed=0, training_episodes=2, evaluation_episodes=1,
                        session_id='golden', record=False, checkpoints=False,
                        overrides={'sim.episode_duration': 8.0, 'agent.horizon': 80,
                                   'sim.human_period': human_period})


@pytest.mark.parametrize('case', sorted(BEFORE_HUMAN_SLICES))
def test_the_old_rate_reproduces_the_sessions_from_before(case):
    assert session_digest(config(case, 0.2)) == BEFORE_HUMAN_SLICES[case]


def test_the_human_rate_changes_the_session_and_sends_a_wrench_per_slice():
    digest, messages = session_digest(config(5, 0.02))
    assert digest != BEFORE_HUMAN_SLICES[5][0]
    # 3 episodes x 40 steps: 9 more human wrenches per step (one per slice state)
    assert messages - BEFORE_HUMAN_SLICES[5][1] == 3 * 40 * 9
