"""Partners first (cases 7, 8): pre-training with a population, then the person in the engine.

Tiny and deterministic: 10-step episodes, a task tree whose tolerances every state meets (so
each step converges as soon as its rule allows), one-episode convergence windows.
"""

from dataclasses import asdict
import json
import math
from types import SimpleNamespace

import pytest
import yaml

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import read_checkpoint
from hrc_agent_node.config import AgentParams
from hrc_common.contract import EpisodeKind, SimLimits
from hrc_common.params import with_overrides
from hrc_common.paths import params_dir
from hrc_common.session_plan import SessionSettings
from hrc_testing.sessions import easy_task_tree
from hrc_engine.engine import compose_parameters, EngineConfig, run_session
from hrc_engine.partners import (make_partner, MixturePartner, parse_specs, person_seed,
                                 SimulatedHumanPartner)
from hrc_joystick_node.human_profile import load_profile
from hrc_joystick_node.population import sample_person
from hrc_partners.partners_first import (default_population, main, person_spec_of,
                                         population_settings, PopulationSettings,
                                         POPULATION_FIRST_PERSON, prepare_person_session,
                                         pretrain, unlike_people)
from hrc_partners.training import training_partner
from hrc_sim_node.physics import PhysicsParams

SHORT = {'sim.episode_duration': 2.0, 'agent.horizon': 20, 'agent.minibatch_size': 10,
         'agent.convergence_window': 1}


@pytest.fixture
def easy_tree(tmp_path):
    """Return a task tree file whose tolerances any state of the episode meets."""
    return easy_task_tree(tmp_path)


def test_the_population_leaves_out_the_sessions_people():
    population = default_population()
    assert len(population) == 24 and len(set(population)) == 24
    for spec in population:
        kind, profile, number = spec.split(':')
        assert kind == 'person' and profile in ('paper', 'novice', 'skilled')
        assert int(number) >= POPULATION_FIRST_PERSON   # the experiment's people are 0, 1, ...
    assert person_spec_of({'profile': 'paper', 'person': 3}) == 'person:paper:3'
    assert person_spec_of({'profile': 'novice', 'person': -1}) == 'profile:novice'
    assert person_spec_of({'input': 'model', 'model_file': 'm.pt'}) == 'model:m.pt'


@pytest.mark.slow
def test_pretraining_meets_the_population_only_and_stops_at_the_persons_step(tmp_path,
                                                                           easy_tree):
    physics = with_overrides(PhysicsParams(), episode_duration=2.0)
    params = with_overrides(AgentParams(), case=7, seed=2, horizon=20, minibatch_size=10,
                            convergence_window=1,
                            task_tree_file=easy_tree, checkpoint_dir='', torch_threads=1)
    population = ['person:novice:1000', 'person:skilled:1001', 'person:paper:1002']
    result = pretrain(params, physics, tmp_path / 'pre.pt', 'person:paper:2', population)
    assert result.reached_person_step
    assert result.population_episodes == len(result.partners_met) > 0
    assert set(result.partners_met) <= set(population)
    assert 'person:paper:2' not in result.partners_met
    core = read_checkpoint(tmp_path / 'pre.pt')['core']
    assert core['progress']['step_index'] == 2            # the person's step, not begun
    assert core['counters']['human_involved_episodes'] == 0
    assert core['counters']['population_episodes'] == result.population_episodes
    # the same seed meets the same partners
    again = pretrain(params, physics, tmp_path / 'again.pt', 'person:paper:2', population)
    assert again.partners_met == result.partners_met
    with pytest.raises(ValueError, match='is in the training population'):
        pretrain(params, physics, tmp_path / 'x.pt', 'person:paper:1002', population)
    with pytest.raises(ValueError, match='has no population step'):
        pretrain(with_overrides(params, case=2), physics, tmp_path / 'y.pt', 'profile:paper',
                 population)


@pytest.mark.slow
@pytest.mark.parametrize('case', [7, 8])
def test_a_partners_first_session_in_the_engine_runs_its_phases_in_order(tmp_path, easy_tree,
                                                                       case):
    config = EngineConfig(SessionSettings(
        case=case, seed=1, training_episodes=40, evaluation_episodes=1, session_id=f'pf{case}',
        bags_dir=str(tmp_path / 'bags'), runs_dir=str(tmp_path / 'runs'),
        overrides=dict(SHORT, **{'agent.task_tree_file': easy_tree, 'human.person': 1})))
    _, parameters = compose_parameters(config)
    start = prepare_person_session(parameters, tmp_path / 'runs' / f'pf{case}')
    record = json.loads((tmp_path / 'runs' / f'pf{case}' / 'pretrain.json').read_text())
    assert record['person'] == 'person:paper:1' and record['reached_person_step']
    assert record['person'] not in record['population']
    assert start['max_training_episodes'] == record['episodes'] + 40
    config.settings.resume_from = start['resume_from']
    config.settings.training_episodes = start['max_training_episodes']
    result = run_session(config)
    assert result.converged and result.strategy == 'partners_first'
    kinds = [(EpisodeKind(e['kind']).label, e['training_step']) for e in result.episodes]
    # the person's step only, judged first: the pre-trained policy meets it at once
    assert kinds == [('judging', 2), ('evaluation', 2)]
    assert result.human_involved_episodes == 1
    assert result.training_episodes == record['episodes'] + 1
    assert result.episodes[0]['episode'] == record['episodes']   # numbering goes on
    bags = sorted(path.name for path in (tmp_path / 'bags' / f'pf{case}').glob('*_episode*.mcap'))
    first = record['episodes']
    assert bags == [f'pf{case}_episode{number:04d}.mcap' for number in (first + 1, first + 2)]
    # the paper's cases need no pre-training
    _, paper = compose_parameters(EngineConfig(SessionSettings(case=2,
                                                                    overrides=dict(SHORT))))
    assert prepare_person_session(paper, tmp_path / 'none') is None


def test_unlike_people_change_one_trait_each():
    person = load_profile('paper')
    people = unlike_people(person)
    assert list(people) == ['slower', 'heavier_handed', 'lapsing', 'timid']
    assert people['slower'].reaction_delay == pytest.approx(2.5 * person.reaction_delay)
    assert people['timid'].slider_full_scale > person.slider_full_scale \
        > people['heavier_handed'].slider_full_scale
    assert people['lapsing'].lapse_probability > person.lapse_probability
    assert people['lapsing'].reaction_delay == person.reaction_delay


@pytest.mark.slow
def test_a_population_step_that_cannot_be_met_ends_after_its_budget(tmp_path):
    tree = yaml.safe_load((params_dir() / 'task_tree.yaml').read_text())
    for subtask in tree['subtasks']:
        # alone the robot meets its own subtask at once; nobody can meet the ball's
        subtask['tolerance'] = 1e-9 if subtask['id'] == 'ball' else 100.0
    path = tmp_path / 'tree.yaml'
    path.write_text(yaml.safe_dump(tree))
    physics = with_overrides(PhysicsParams(), episode_duration=2.0)
    params = with_overrides(AgentParams(), case=8, seed=4, horizon=20, minibatch_size=10,
                            convergence_window=1,
                            task_tree_file=str(path), checkpoint_dir='', torch_threads=1)
    result = pretrain(params, physics, tmp_path / 'pre.pt', 'person:paper:4',
                      population_budget=3)
    assert result.reached_person_step and not result.population_met
    assert result.population_episodes == len(result.partners_met) == 3
    assert read_checkpoint(tmp_path / 'pre.pt')['core']['progress']['step_index'] == 2


def test_the_command_line_refuses_bad_input_with_every_reason(capsys):
    assert main(['--case', '8', '--set', 'agent.gamma=3', '--set', 'agent.horizon=0']) == 2
    error = capsys.readouterr().err
    assert 'gamma: 3.0 is above the maximum 1.0' in error and 'horizon: 0 is below' in error
    assert main(['--case', '2']) == 2
    assert 'case 2 has no population step' in capsys.readouterr().err
    assert main(['--case', '9']) == 2
    assert 'case must be one of 1..8, got 9' in capsys.readouterr().err


def _commands(partner, dof, steps=60, episode=0):
    """Return ``partner``'s commands over a fixed swinging state (deterministic, no sim)."""
    partner.start_episode(episode)
    commands = []
    for index in range(steps):
        state = SimpleNamespace(slider_position=0.02 * math.sin(0.3 * index),
                                slider_velocity=0.006 * math.cos(0.3 * index),
                                pendulum_angle=0.15 * math.cos(0.2 * index),
                                pendulum_angular_velocity=-0.03 * math.sin(0.2 * index),
                                ball_position=0.1 * math.sin(0.1 * index),
                                ball_velocity=0.01 * math.cos(0.1 * index))
        commands.append(partner(state, ['pendulum' if dof == 'rotation' else 'slider', 'ball']))
    return commands


@pytest.mark.parametrize('spec', ['person:paper:1000', 'profile:skilled', 'population:novice'])
def test_the_training_people_act_at_the_humans_rate_as_the_sessions_person(spec):
    # The offline loop calls a simulated person every human_period (0.02 s by default), and
    # the engine's person is a SimulatedHuman built for that period (human_core); a training
    # person built for the control period ran its delays and integrator 10x fast.
    limits = SimLimits.of(PhysicsParams())
    assert limits.human_step == pytest.approx(0.02) and limits.control_period == pytest.approx(0.2)
    mixture = MixturePartner(parse_specs([spec]), 'rotation', 3, limits)
    mixture.start_episode(0)
    assert mixture.partner.human.control_period == pytest.approx(limits.human_step)
    direct = make_partner(parse_specs([spec])[0], 'rotation', 3, limits)
    direct.start_episode(0)
    assert direct.human.control_period == pytest.approx(limits.human_step)


def test_a_training_person_acts_as_the_engines_person():
    limits = SimLimits.of(PhysicsParams())
    person = sample_person(load_profile('paper'), 1000)
    seed = person_seed(5, 0)      # the MixturePartner's first draw's person seed
    mixture = MixturePartner(parse_specs(['person:paper:1000']), 'rotation', 5, limits)
    # the engine's person (human_core): a SimulatedHuman built for the human period
    reference = SimulatedHumanPartner(person, 'rotation', seed, limits.human_step)
    assert _commands(mixture, 'rotation') == _commands(reference, 'rotation')


def test_the_population_block_of_the_cases_file_mirrors_the_defaults(tmp_path):
    cases = yaml.safe_load((params_dir() / 'cases.yaml').read_text())
    block = cases['strategies']['partners_first']['population']
    assert block == asdict(PopulationSettings())
    assert population_settings(params_dir() / 'cases.yaml').population() == default_population()
    cases['strategies']['partners_first']['population'] = dict(
        block, profiles=[], budget=-1, first_person=-1)
    bad = tmp_path / 'cases.yaml'
    bad.write_text(yaml.safe_dump(cases))
    with pytest.raises(ValueError) as error:
        population_settings(bad)
    for reason in ('budget: -1 is below the minimum 0', 'first_person: -1 is below',
                   'profiles: a non-empty list'):
        assert reason in str(error.value)
    # the command line: exit 2, every reason, no traceback
    assert main(['--case', '7', '--set', f'agent.cases_file={bad}']) == 2


@pytest.mark.slow
def test_the_pretraining_can_take_fewer_sac_gradient_steps_than_the_session(tmp_path,
                                                                             easy_tree):
    physics = with_overrides(PhysicsParams(), episode_duration=2.0)
    params = with_overrides(AgentParams(), case=8, seed=1, algorithm='sac',
                            sac_learning_starts=5, sac_batch_size=4, sac_hidden_size=8,
                            sac_updates_per_step=3, convergence_window=1,
                            task_tree_file=easy_tree,
                            checkpoint_dir='', torch_threads=1)
    steps = {}
    for setting in (0, 1):
        result = pretrain(params, physics, tmp_path / f'pre{setting}.pt', 'person:paper:1',
                          ['person:paper:1001'], sac_updates_per_step=setting)
        checkpoint = read_checkpoint(tmp_path / f'pre{setting}.pt')
        assert checkpoint['config']['params']['sac_updates_per_step'] == (setting or 3)
        assert result.sac_updates_per_step == setting and result.reached_person_step
        steps[setting] = (checkpoint['core']['sac']['gradient_steps'], result.episodes)
    # the same transitions (episodes), a third of the critic steps (plus no actor change)
    assert steps[0][1] == steps[1][1]
    assert steps[0][0] == 3 * steps[1][0] > 0


def test_hrc_partners_train_meets_its_person_at_the_humans_rate():
    limits = SimLimits.of(PhysicsParams())
    core = AgentCore(with_overrides(AgentParams(), case=2, checkpoint_dir='', torch_threads=1),
                     limits=limits)
    partner, text = training_partner(core, 0, limits, 'paper', 0)
    partner.start_episode(0)
    assert partner.human.control_period == pytest.approx(limits.human_step)
    assert text == 'profile:paper'
    mixture, text = training_partner(core, 0, limits, 'paper', 1, mixture=['population:novice'])
    mixture.start_episode(0)
    assert mixture.partner.human.control_period == pytest.approx(limits.human_step)
