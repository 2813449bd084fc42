"""The partners-first strategy in AgentCore (cases 7 and 8): step order, who counts, judge first.

Deterministic: seeded cores driven with hand-made states (no physics), as in
test_agent_convergence.py.
"""

import pytest

from hrc_agent_node.agent_core import AgentCore, PopulationStepRefused
from hrc_agent_node.checkpoint import load_into, save_checkpoint
from hrc_agent_node.config import AgentParams
from hrc_common.contract import Phase, SimLimits
from hrc_common.params import with_overrides

STEPS = 4
LIMITS = SimLimits(control_period=0.2, max_force=2.0, max_torque=0.5)
GOOD = dict(slider=0.0, angle=0.0, ball=0.0)       # every subtask satisfied
BAD = dict(slider=0.09, angle=1.0, ball=0.2)       # none satisfied


class State:
    """A hand-made state with the attributes AgentCore reads."""

    def __init__(self, step, final=False, slider=0.0, angle=0.0, ball=0.0):
        self.step, self.truncated, self.terminated = step, final, False
        self.slider_position, self.pendulum_angle, self.ball_position = slider, angle, ball
        self.slider_velocity = self.pendulum_angular_velocity = self.ball_velocity = 0.0
        self.applied_force = self.applied_torque = 0.0


def make_core(case=8, **overrides):
    values = dict(case=case, seed=3, preset='tuned', checkpoint_dir='', horizon=8,
                  minibatch_size=4, convergence_window=2, satisfied_window=2,
                  max_training_episodes=100, evaluation_episodes=1)
    values.update(overrides)
    return AgentCore(with_overrides(AgentParams(), **values), limits=LIMITS)


def run_episode(core, training=BAD, judging=GOOD):
    plan = core.start_episode()
    values = judging if plan.deterministic else training
    for step in range(STEPS):
        core.act(State(step, **values))
    result = core.end_episode(State(STEPS, final=True, **values))
    if core.phase == Phase.UPDATING:
        core.update()
    return plan, result


@pytest.mark.parametrize('case', [7, 8])
def test_alone_then_population_then_the_person_who_alone_counts(case):
    core = make_core(case)
    core.population_partner = True          # as hrc_partners.partners_first.pretrain does
    plans = []
    while core.phase != Phase.DONE:
        plans.append(run_episode(core)[0])
    steps = [plan.training_step for plan in plans if not plan.evaluation]
    assert steps == sorted(steps) and set(steps) == {0, 1, 2}   # in order, none skipped
    alone = [plan for plan in plans if plan.training_step == 0]
    population = [plan for plan in plans if plan.training_step == 1]
    person = [plan for plan in plans if plan.training_step == 2 and not plan.evaluation]
    assert not any(plan.human_involved for plan in alone)
    assert all(plan.human_involved and plan.partner == 'population' and not plan.with_person
               for plan in population)
    assert all(plan.with_person for plan in person)
    # judge_first: the person's step starts by judging the policy it inherits; it meets the
    # step at once, and in_a_row judges it again: the person's whole step is 2 episodes
    assert [plan.judging for plan in person] == [True, True]
    assert core.human_involved_episodes == len(person) == 2
    assert core.population_episodes == len(population)
    assert core.total_episodes == len(alone) + len(population) + len(person)
    summary = core.evaluation_summary()
    assert summary['human_involved_episodes'] == 2
    assert summary['population_episodes'] == len(population)


def test_the_paper_cases_have_no_population_episodes_in_their_summary():
    core = make_core(case=5, max_training_episodes=2)
    while core.phase != Phase.DONE:
        run_episode(core)
    assert core.human_involved_episodes == 2 and core.population_episodes == 0
    assert 'population_episodes' not in core.evaluation_summary()


def test_a_population_step_needs_a_population_partner():
    core = make_core(8)
    while core.training_step.index == 0:      # alone: no partner needed
        assert core.population_step_problem() == ''
        run_episode(core)
    problem = core.population_step_problem()
    assert 'python -m hrc_partners.partners_first --case 8' in problem
    # a ValueError: the engine and the agent node refuse it (exit 2), no traceback
    with pytest.raises(PopulationStepRefused, match='pre-train it first') as error:
        core.start_episode()
    assert isinstance(error.value, ValueError) and str(error.value) == problem
    core.population_partner = True
    assert core.population_step_problem() == ''


def test_a_session_resumed_at_the_person_step_runs_with_the_person(tmp_path):
    trainer = make_core(7)
    trainer.population_partner = True
    while trainer.training_step.index < 2:
        run_episode(trainer)
    save_checkpoint(trainer, tmp_path / 'pretrained.pt')
    session = make_core(7)                       # population_partner stays False
    load_into(session, tmp_path / 'pretrained.pt')
    assert session.training_step.with_person and session.human_involved_episodes == 0
    assert session.population_episodes == trainer.population_episodes > 0
    plan, _ = run_episode(session)
    assert plan.judging and plan.with_person and session.human_involved_episodes == 1


def test_a_step_skipped_between_episodes_starts_the_next_one():
    core = make_core(8)
    core.population_partner = True
    while core.training_step.index == 0:
        run_episode(core)
    run_episode(core, training=BAD, judging=BAD)        # the population step, unmet
    assert core.training_step.index == 1 and core.phase == Phase.TRAINING
    core.skip_step()
    assert core.training_step.with_person
    plan, _ = run_episode(core)
    assert plan.training_step == 2 and plan.judging     # judge_first holds after a skip too
    with pytest.raises(RuntimeError, match='only a step before the last one'):
        core.skip_step()
