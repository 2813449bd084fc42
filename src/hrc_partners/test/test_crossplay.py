"""Cross-play of a (briefly) trained agent with partners: matrix, intervals, drops, heatmap."""

import json
import math

from PIL import Image
import pytest

from hrc_partners import crossplay, crossplay_cli, training
from hrc_engine.partners import parse_specs


@pytest.mark.slow
def test_matrix_files_and_drops(tmp_path, capsys):
    checkpoint = tmp_path / 'c2-one-s0.pt'
    summary = training.train_agent(2, 0, 2, 'paper', 0, 'tuned', checkpoint)
    (tmp_path / 'c2-one-s0.json').write_text(json.dumps(summary))
    assert summary['training_partner'] == 'profile:paper'
    code = crossplay_cli.main(['--agent', f'one={checkpoint}', '--partner', 'person:paper:7',
                               'population:paper', '--seeds', '0', '1', '--episodes', '1',
                               '--out', str(tmp_path / 'out'), '--quiet'])
    assert code == 0
    printed = capsys.readouterr().out
    result = json.loads((tmp_path / 'out' / 'matrix.json').read_text())
    # the training partner is added as a column; one error per seed in every cell
    assert result['partners'] == ['person:paper:7', 'population:paper', 'profile:paper']
    cells = result['cells']['one']
    for partner, cell in cells.items():
        assert len(cell['errors']) == 2 and all(value > 0 for value in cell['errors'])
        assert cell['low'] <= cell['mean'] <= cell['high']
        assert math.isclose(cell['drop'], cell['mean'] / cells['profile:paper']['mean'])
    assert cells['profile:paper']['drop'] == 1.0
    # different seeds give different sessions (the interval is over something)
    assert cells['person:paper:7']['errors'][0] != cells['person:paper:7']['errors'][1]
    assert '| one (profile:paper) |' in printed and '1.00x' in printed
    with Image.open(tmp_path / 'out' / 'heatmap.png') as image:
        assert image.size[0] > 200 and image.size[1] > 100


def test_same_seed_same_error(tmp_path):
    checkpoint = tmp_path / 'a.pt'
    training.train_agent(2, 1, 1, 'paper', 0, 'tuned', checkpoint)
    agents = [crossplay.Agent('a', str(checkpoint), 'profile:paper')]
    first = crossplay.run_matrix(agents, ['person:paper:2'], [4], 1)
    second = crossplay.run_matrix(agents, ['person:paper:2'], [4], 1)
    assert first.errors == second.errors


def test_bad_agents_and_partners_every_reason(tmp_path, capsys):
    code = crossplay_cli.main(['--agent', 'x', f'y={tmp_path}/none.pt', '--partner', 'who:me',
                               'person:paper:x', f'model:{tmp_path}/none.pt', '--episodes',
                               '0'])
    assert code == 2
    error = capsys.readouterr().err
    for reason in ("partner 'who:me'", "partner 'person:paper:x'", 'no such model file',
                   "agent 'x'", 'no such checkpoint', '--episodes'):
        assert reason in error, reason
    assert 'Traceback' not in error


def test_specs():
    spec = parse_specs(['person:paper:12'])[0]
    assert (spec.kind, spec.name, spec.person) == ('person', 'paper', 12)


def test_mixture_population_draws_profiles_people_and_clones(tmp_path):
    from hrc_common.contract import SimLimits
    from hrc_joystick_node.human_model import build_network, save_human_model
    from hrc_engine.partners import MixturePartner, parse_spec
    from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

    config = {'history_steps': 2, 'hidden': [4], 'dof': 'translation', 'control_period': 0.2,
              'description': 'test'}
    save_human_model(tmp_path / 'm.pt', config, build_network(config).state_dict())
    spec = parse_spec(f'mixture:population:paper+model:{tmp_path / "m.pt"}')
    assert [part.kind for part in spec.parts] == ['population', 'model']

    def draws(seed):
        physics = PhysicsParams()
        partner = MixturePartner(spec.parts, 'translation', seed, SimLimits.of(physics), every=2)
        with SliderPendulumBall(physics) as sim:
            state = sim.reset(0)
            for episode in range(12):
                partner.start_episode(episode)
                assert -1.0 <= partner(state, ['slider', 'ball']) <= 1.0
        return partner.drawn

    first = draws(0)
    assert [draw for draw, _ in first] == list(range(6))        # a new partner every 2
    assert {text for _, text in first} == {part.text for part in spec.parts}
    assert draws(0) == first
