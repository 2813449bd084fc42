"""The learning configurations (params/learning/*.yaml) are valid agent parameters.

Each one names only AgentParams fields with values the agent accepts; the ``paper`` one is
Table I and the paper's reward literally (the agent's own defaults); a retired parameter in a
file or a --set is refused with where its behaviour lives.
"""

import pytest

from hrc_agent_node.config import AgentParams
from hrc_common.params import as_dict, from_dict, ParameterError
from hrc_common.paths import params_dir
from hrc_common.session_plan import learning_names, load_learning

# Table I of the paper (PPO) and its reward preset
TABLE_I = dict(algorithm='ppo', preset='paper', gamma=0.995, gae_lambda=0.95, horizon=512,
               minibatch_size=64, epochs=3, learning_rate=0.001, clip_coef=0.05,
               entropy_coef=0.02)


def test_the_configurations_exist_and_are_agent_parameters():
    assert learning_names(params_dir()) == ['paper', 'partner_aware', 'ppo', 'sac']
    for name in learning_names(params_dir()):
        values = load_learning(params_dir(), name)
        params = from_dict(AgentParams, values)        # raises with every reason if not
        assert {key: as_dict(params)[key] for key in values} == values, name


def test_the_paper_configuration_is_table_one_and_the_agents_defaults():
    paper = load_learning(params_dir(), 'paper')
    assert {key: paper[key] for key in TABLE_I} == TABLE_I
    defaults = as_dict(AgentParams())
    assert {key: defaults[key] for key in TABLE_I} == TABLE_I


def test_the_default_learns_with_sac_and_the_ppo_one_with_the_studys_rules():
    sac, ppo = load_learning(params_dir(), 'sac'), load_learning(params_dir(), 'ppo')
    assert (sac['algorithm'], sac['preset'], sac['judging_interval']) == ('sac', 'tuned', 2)
    assert (ppo['algorithm'], ppo['preset'], ppo['epochs'], ppo['clip_coef']) == \
        ('ppo', 'graded', 10, 0.2)


@pytest.mark.parametrize('name', ['update_rule', 'judging_rule', 'convergence_judged_on'])
def test_a_retired_parameter_is_refused_with_where_its_behaviour_lives(name):
    with pytest.raises(ParameterError, match=rf"parameter '{name}' was retired: .*git 8c1b998"):
        from_dict(AgentParams, {name: 'anything'})


def test_the_partner_aware_configuration_is_sac_with_the_partner_model():
    sac, aware = load_learning(params_dir(), 'sac'), load_learning(params_dir(), 'partner_aware')
    assert aware == dict(sac, partner_inference=True)
