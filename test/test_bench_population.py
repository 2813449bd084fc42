"""bench/population.py's simulated people act at the sim's human period, as the engine's.

The sessions are replaced by a recorder of the partner (no training, no sim steps).
"""

import importlib.util
import pathlib

import pytest

from hrc_common.contract import SimLimits
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


def test_training_and_evaluation_people_act_at_the_humans_rate(population):
    limits = SimLimits.of(PhysicsParams())
    assert limits.human_step == pytest.approx(0.02) and limits.control_period == pytest.approx(0.2)
    core, _ = population.train(2, 0, 1, 'paper', 1, 'tuned')
    population.evaluate(core, load_profile('paper'), 0, 0, 1)
    population.evaluate(core, load_profile('paper'), 1, 5000, 1)
    assert [partner.control_period for partner in population.partners] == [limits.human_step] * 3
    assert [partner.population_every for partner in population.partners] == [1, 0, 1]
