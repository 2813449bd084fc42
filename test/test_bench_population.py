"""bench/population.py's simulated people act at the study's rate (issue 22's leftovers).

The offline loop calls a person every human_period (0.02 s by default); the bench's evaluation
people were built for the control period (0.2 s), so their delays and integrator ran 10x fast.
The sessions are replaced by a recorder of the partner (no training, no sim steps).
"""

import importlib.util
import pathlib

import pytest

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides
from hrc_joystick_node.human_profile import load_profile
from hrc_sim_node.physics import PhysicsParams

BENCH = pathlib.Path(__file__).resolve().parents[1] / 'bench' / 'population.py'


@pytest.fixture
def population(monkeypatch):
    """Return the bench module, its sessions replaced: the partners they got are in .partners."""
    spec = importlib.util.spec_from_file_location('population_bench', BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.partners = []

    def record(core, sim, partner):
        module.partners.append(partner)
        return {'training_episodes': 0, 'converged': False, 'evaluation': {'total_error': 1.0}}

    monkeypatch.setattr(module, 'run_session', record)
    return module


@pytest.mark.parametrize('period', ['human', 'control'])
def test_training_and_evaluation_people_act_every_person_period(population, period):
    limits = SimLimits.of(PhysicsParams())
    assert limits.human_step == pytest.approx(0.02) and limits.control_period == pytest.approx(0.2)
    seconds = limits.human_step if period == 'human' else limits.control_period
    core, _ = population.train(2, 0, 1, 'paper', 1, 'tuned', period)
    population.evaluate(core, load_profile('paper'), 0, 0, 1, period)
    population.evaluate(core, load_profile('paper'), 1, 5000, 1, period)
    assert [partner.control_period for partner in population.partners] == [seconds] * 3
    assert [partner.population_every for partner in population.partners] == [1, 0, 1]


def test_the_command_line_gives_every_person_its_period(population, monkeypatch, capsys):
    core = AgentCore(with_overrides(AgentParams(), case=2, seed=0),
                     limits=SimLimits.of(PhysicsParams()))
    periods = []
    monkeypatch.setattr(population, 'train', lambda *arguments: (
        periods.append(arguments[-1]) or core, {'training_episodes': 1, 'converged': True}))
    monkeypatch.setattr(population, 'evaluate', lambda *arguments: (
        periods.append(arguments[-1]) or 1.0))
    assert population.main(['--held-out', '1']) == 0
    assert set(periods) == {'human'} and len(periods) == 2 * (1 + 3)   # train, 3 evaluations
    periods.clear()
    assert population.main(['--held-out', '1', '--person-period', 'control']) == 0
    assert set(periods) == {'control'} and len(periods) == 8
    with pytest.raises(SystemExit):
        population.main(['--person-period', 'often'])
    assert "invalid choice: 'often'" in capsys.readouterr().err
