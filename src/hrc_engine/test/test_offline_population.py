"""Population training in the offline loop: a new simulated person every N episodes, seeded."""

import pytest

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_engine.offline import make_partner, run_session
from hrc_engine.partners import SimulatedHumanPartner
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides
from hrc_joystick_node.human_profile import load_profile
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

CONTROL_PERIOD = 0.2   # s: the sim's control period (params/sim.yaml), the people's call period
PROFILE = load_profile('paper')


def persons(partner, episodes):
    """Return the person met in each of ``episodes`` episodes."""
    met = []
    for episode in range(episodes):
        partner.start_episode(episode)
        met.append(partner.person)
    return met


def test_without_population_one_person_the_profile_itself():
    partner = SimulatedHumanPartner(PROFILE, 'rotation', seed=3, control_period=CONTROL_PERIOD)
    partner.start_episode(0)
    human = partner.human
    assert persons(partner, 4) == [PROFILE] * 4 and partner.human is human


def test_a_new_person_every_episode_reproducible_from_the_seed():
    met = persons(SimulatedHumanPartner(PROFILE, 'rotation', seed=3, population_every=1,
                                        control_period=CONTROL_PERIOD), 5)
    assert len({person.reaction_delay for person in met}) == 5
    assert all(person != PROFILE for person in met)
    assert met == persons(SimulatedHumanPartner(PROFILE, 'rotation', seed=3,
                                                population_every=1,
                                                control_period=CONTROL_PERIOD), 5)
    other = persons(SimulatedHumanPartner(PROFILE, 'rotation', seed=4, population_every=1,
                                          control_period=CONTROL_PERIOD), 5)
    assert [p.reaction_delay for p in other] != [p.reaction_delay for p in met]


def test_a_new_person_every_batch_of_episodes():
    met = persons(SimulatedHumanPartner(PROFILE, 'translation', seed=1, population_every=3,
                                        control_period=CONTROL_PERIOD), 7)
    assert met[0] == met[1] == met[2] != met[3]
    assert met[3] == met[4] == met[5] != met[6]


def test_offline_loop_meets_the_population_in_every_kind_of_episode():
    """Case 5 (human from the start), 2 s episodes: each episode's person is drawn anew."""
    physics = PhysicsParams(episode_duration=2.0)
    core = AgentCore(with_overrides(
        AgentParams(), case=5, seed=2, preset='tuned', checkpoint_dir='', horizon=20,
        minibatch_size=10, max_training_episodes=4, evaluation_episodes=1))
    partner = make_partner(core, seed=2, kind='human:paper', population_every=1,
                           limits=SimLimits.of(physics))
    met = []
    with SliderPendulumBall(physics) as sim:
        run_session(core, sim, partner,
                    on_episode=lambda result, stats: met.append(
                        (result.judging, result.evaluation, partner.draw,
                         partner.person.reaction_delay, result.human_effort)))
    assert [draw for _, _, draw, _, _ in met] == list(range(5))
    assert any(judging for judging, _, _, _, _ in met) and met[-1][1]
    assert len({delay for _, _, _, delay, _ in met}) == 5
    assert all(effort > 0.0 for _, _, _, _, effort in met)   # the person acted every time


def test_unknown_partner_kind_is_refused():
    core = AgentCore(with_overrides(AgentParams(), case=2, checkpoint_dir=''))
    with pytest.raises(ValueError, match="expected 'scripted' or 'human:<profile>'"):
        make_partner(core, kind='robot')
