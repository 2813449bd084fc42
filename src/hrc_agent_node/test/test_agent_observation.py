"""What the robot observes as the human action (human_action_source)."""

import pytest

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall


def core_for(case, source):
    """Return an AgentCore of ``case`` (5 and 6 involve the human from the first episode)."""
    return AgentCore(with_overrides(AgentParams(), case=case, seed=3, checkpoint_dir='',
                                    human_action_source=source),
                     limits=SimLimits.of(PhysicsParams()))


def test_applied_source_reads_the_human_command_the_sim_applied():
    # Case 5 (learn together): the human rotates and is involved from the start.
    core = core_for(5, 'applied')
    assert core.human_involved and core.human_dof == 'rotation'
    assert not core.needs_human_action
    with SliderPendulumBall(PhysicsParams()) as sim:
        core.start_episode()
        state = sim.reset(seed=1)
        # A same-step answer would not be used: refused, never silently ignored.
        with pytest.raises(ValueError, match='human_action_source is applied'):
            core.act(state, human_action=0.9)
        first = core.act(state)
        assert first.record.observed_human_action == 0.0   # nothing applied yet
        state = sim.step_normalized(first.action, -0.4)   # the human turned at -0.4
        second = core.act(state)
        assert abs(second.record.observed_human_action - (-0.4)) < 1e-9
        # An out-of-range human command is observed as the sim applied it: clamped.
        state = sim.step(0.0, 5 * PhysicsParams().max_torque)
        assert core.act(state).record.observed_human_action == 1.0


def test_same_step_source_observes_the_answer_to_the_same_state():
    core = core_for(6, 'same_step')
    assert core.human_involved and core.human_dof == 'translation'
    assert core.needs_human_action
    with SliderPendulumBall(PhysicsParams()) as sim:
        core.start_episode()
        state = sim.reset(seed=1)
        with pytest.raises(ValueError, match="needs the human's answer"):
            core.act(state)
        assert core.act(state, human_action=0.3).record.observed_human_action == 0.3


def test_same_step_episode_ending_at_its_first_state_needs_no_answer():
    """States lost: the final state arrives first; the episode closes without a human answer."""
    core = core_for(6, 'same_step')
    with SliderPendulumBall(PhysicsParams(episode_duration=0.4)) as sim:
        core.start_episode()
        sim.reset(seed=1)
        state = sim.step_normalized(0.0, 0.0)
        final = sim.step_normalized(0.0, 0.0)
        assert final.truncated and not state.truncated
        result = core.end_episode(final)
    assert result.steps == 0 and core.total_episodes == 1
