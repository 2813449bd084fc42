"""What the robot observes as the human action (human_action_source)."""

import numpy as np
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


def test_the_humans_effort_is_that_of_every_command_applied_at_its_rate():
    """At the human's rate the effort is that of every command the sim applied.

    The robot observes the period's mean; the effort reported is the variance of the
    person's real input.
    """
    from hrc_sim_node.stepper import PeriodState

    params = PhysicsParams(episode_duration=0.6)
    slices = params.human_slices
    core = core_for(5, 'applied')
    full_scale = params.max_torque
    applied = []
    with SliderPendulumBall(params) as sim:
        core.start_episode()
        state = PeriodState(sim.reset(seed=1), ())
        while not state.truncated:
            decision = core.act(state)
            commands = [0.5 * (-1) ** index * full_scale for index in range(slices)]
            for command in commands:
                sim.advance(decision.action * params.max_force, command,
                            params.substeps_per_slice)
            state = PeriodState(sim.finish_period(), commands)
            applied += [command / full_scale for command in commands]
            # what the robot observes: the period's mean (0 here), not the last slice
            assert abs(state.applied_torque) < 1e-12
        result = core.end_episode(state)
    assert result.human_effort == pytest.approx(np.var(applied)) and result.human_effort > 0.2
    # One command a period (the human held it): the observed actions, as before.
    core = core_for(5, 'applied')
    with SliderPendulumBall(params) as sim:
        core.start_episode()
        state = sim.reset(seed=1)
        observed = []
        while not state.truncated:
            observed.append(core.act(state).record.observed_human_action)
            state = PeriodState(sim.step(0.0, 0.3 * full_scale), [0.3 * full_scale])
        assert core.end_episode(state).human_effort == pytest.approx(np.var(observed))
