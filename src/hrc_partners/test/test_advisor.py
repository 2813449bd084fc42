"""Role allocation advisor on simulated people with known asymmetric skills.

The robot is the scripted PD controller with command noise, standing in for a trained robot
(said in the advice): fast and deterministic for a seed.
"""

from hrc_joystick_node.human_profile import load_profile
import pytest
from hrc_partners import advisor


@pytest.mark.slow
def test_right_in_clear_cases_and_quick_for_the_person():
    plan = advisor.CalibrationPlan()
    assert plan.person_seconds < 180.0
    results = advisor.validate(14, plan, seed=0)
    clear = [draw for draw in results if draw.better in advisor.DOFS]
    assert len(clear) >= 10, advisor.validation_table(results)
    assert sum(draw.correct for draw in clear) >= 0.9 * len(clear), \
        advisor.validation_table(results)
    # both directions occur: the advice depends on the person, not on the robot alone
    assert {draw.better for draw in clear} == set(advisor.DOFS)
    # never the worse assignment where the long run separates them
    assert not any(draw.advice.recommended and draw.better in advisor.DOFS
                   and draw.advice.recommended != draw.better for draw in results)


def test_no_clear_difference_when_the_intervals_do_not_separate():
    def assignment(dof, errors):
        return advisor.Assignment(dof, 'test', errors, errors)

    overlapping = {'translation': assignment('translation', [0.20, 0.25, 0.22, 0.27]),
                   'rotation': assignment('rotation', [0.24, 0.21, 0.26, 0.23])}
    assert advisor.recommend(overlapping) == ''
    separated = {'translation': assignment('translation', [0.20, 0.21, 0.22, 0.20]),
                 'rotation': assignment('rotation', [0.30, 0.32, 0.31, 0.33])}
    assert advisor.recommend(separated) == 'translation'
    text = advisor.Advice(overlapping, '', 100.0).describe()
    assert 'no clear difference' in text and 'calibration: 100 s' in text


def test_advice_text_names_the_stand_in():
    weak_at_rotation = advisor.asymmetric_person(load_profile('paper_symmetric'), 3,
                                                 'rotation', 5.0)
    person = advisor.simulated_person(weak_at_rotation, 3)
    robots = {dof: advisor.ScriptedRobot(advisor.other_dof(dof), noise=1.0)
              for dof in advisor.DOFS}
    advice = advisor.calibrate(person, robots, advisor.CalibrationPlan(episodes_per_dof=2))
    text = advice.describe()
    assert 'stand-in for a trained robot' in text
    assert len(advice.assignments['rotation'].team_errors) == 2


def test_a_trained_robot_plays_a_team_episode_with_the_sims_limits(tmp_path):
    """The trained robot's core learns the sim's limits from the episode (it has none itself)."""
    from hrc_agent_node.agent_core import AgentCore
    from hrc_agent_node.checkpoint import save_checkpoint
    from hrc_agent_node.config import AgentParams
    from hrc_common.params import with_overrides
    from hrc_joystick_node.sim_human import SimulatedHuman
    from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

    checkpoint = save_checkpoint(
        AgentCore(with_overrides(AgentParams(), case=2, checkpoint_dir='')), tmp_path / 'c.pt')
    robot = advisor.TrainedRobot(checkpoint)
    assert robot.dof == 'rotation'
    physics = PhysicsParams(episode_duration=2.0, max_torque=0.8)
    with SliderPendulumBall(physics) as sim:
        person = SimulatedHuman(load_profile('paper'), 'translation', seed=0,
                                control_period=physics.control_period)
        person.reset(0)
        team, own = advisor.team_episode(sim, robot, person, 'translation', 0, 0.0)
    assert team > 0.0 and own >= 0.0
    assert robot.core.limits.max_torque == 0.8


def test_the_person_gets_the_sims_control_period():
    # the sim's limits reach the person: a control period set for the sim is the person's too
    given = []

    def person_for(dof, limits):
        given.append(limits)
        return advisor.simulated_person(load_profile('paper'), 0)(dof, limits)

    robots = {dof: advisor.ScriptedRobot(advisor.other_dof(dof)) for dof in advisor.DOFS}
    plan = advisor.CalibrationPlan(episodes_per_dof=1, seconds=1.0)
    advisor.calibrate(person_for, robots, plan, physics_overrides={'control_period': 0.1})
    assert [limits.control_period for limits in given] == [0.1, 0.1]
