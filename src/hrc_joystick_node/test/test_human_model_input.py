"""``input: model``: a cloned human-model checkpoint loaded safely and driven like a person."""

import os
import pickle

import pytest
import torch

from hrc_common.paths import params_dir
from hrc_common.contract import SimLimits
from hrc_common.params import ParameterError
from hrc_joystick_node.human_core import HumanCore, HumanParams
from hrc_joystick_node.human_model import (build_network, ClonedHuman, load_human_model,
                                           save_human_model)
from hrc_joystick_node.inputs import MODEL
from hrc_joystick_node.human_profile import load_profiles

CONTROL_PERIOD = 0.2   # s: the sim's control period (params/sim.yaml), the people's call period
PROFILES = load_profiles(params_dir()
                         / 'sim_human.yaml')
CONFIG = {'history_steps': 3, 'hidden': [8], 'dof': 'rotation', 'control_period': 0.2,
          'description': 'a test model'}


class State:
    """A PhysicsState-like state."""

    def __init__(self, angle=0.0, rate=0.0):
        self.slider_position = self.slider_velocity = 0.0
        self.ball_position = self.ball_velocity = 0.0
        self.pendulum_angle, self.pendulum_angular_velocity = angle, rate


@pytest.fixture
def model_file(tmp_path):
    torch.manual_seed(0)
    path = tmp_path / 'clone.pt'
    save_human_model(path, CONFIG, build_network(CONFIG).state_dict())
    return path


def test_a_cloned_model_loads_and_acts_deterministically(model_file):
    human = ClonedHuman(model_file, 'rotation', control_period=CONTROL_PERIOD)
    states = [State(0.3 - 0.01 * step, -0.05) for step in range(10)]
    first = [human.act(state, ['pendulum']) for state in states]
    human.reset(1)
    assert [human.act(state, ['pendulum']) for state in states] == first
    assert all(-1.0 <= value <= 1.0 for value in first) and len(set(first)) > 1
    human.reset(2)
    assert [human.act(state, ['pendulum', 'ball']) for state in states] != first
    assert human.note == ''
    assert 'cloned on rotation, driving translation' in ClonedHuman(
        model_file, 'translation', control_period=CONTROL_PERIOD).note


class Payload:
    """Runs code when unpickled (a crafted checkpoint)."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, 'w'))


@pytest.mark.parametrize('hidden', [False, True])
def test_a_crafted_checkpoint_is_refused_and_runs_no_code(tmp_path, hidden):
    marker = tmp_path / 'pwned'
    path = tmp_path / 'crafted.pt'
    payload = Payload(marker)
    if hidden:  # inside an otherwise valid checkpoint
        document = {'format': 'hrc-human-model', 'version': 1, 'config': CONFIG,
                    'state_dict': build_network(CONFIG).state_dict(), 'extra': payload}
        torch.save(document, str(path))
    else:
        with open(path, 'wb') as stream:
            pickle.dump(payload, stream)
    with pytest.raises(ParameterError, match='weights_only=True'):
        load_human_model(path)
    assert not marker.exists(), 'the payload ran'


def test_every_problem_of_a_file_is_refused_with_every_reason(tmp_path, model_file):
    path = tmp_path / 'bad.pt'
    state = build_network(CONFIG).state_dict()
    state['0.weight'] = torch.zeros(8, 5)
    state['2.bias'] = torch.tensor([float('nan')])
    state['extra'] = torch.zeros(1)
    torch.save({'format': 'hrc-human-model', 'version': 1, 'config': CONFIG,
                'state_dict': state}, str(path))
    with pytest.raises(ParameterError) as refused:
        load_human_model(path)
    reasons = refused.value.reasons
    assert any('0.weight: shape (8, 5) does not fit' in reason for reason in reasons)
    assert any('2.bias: holds non-finite values' in reason for reason in reasons)
    assert any('unexpected extra' in reason for reason in reasons)

    torch.save({'format': 'other', 'config': {'history_steps': 0, 'hidden': 'wide',
                                              'dof': 'both', 'moods': 1},
                'state_dict': [1]}, str(path))
    with pytest.raises(ParameterError) as refused:
        load_human_model(path)
    text = ' | '.join(refused.value.reasons)
    for expected in ("format: expected 'hrc-human-model'", 'version: expected 1',
                     'history_steps', 'config.hidden', 'config.dof',
                     'config.control_period', "unknown field 'moods'", 'state_dict: expected'):
        assert expected in text
    path.write_bytes(os.urandom(64))
    with pytest.raises(ParameterError, match='not a human-model checkpoint'):
        load_human_model(path)
    with pytest.raises(ParameterError, match='cannot read'):
        load_human_model(tmp_path / 'missing.pt')


def test_the_core_drives_the_human_with_the_model(model_file):
    core = HumanCore(HumanParams(input='model', model_file=str(model_file)), PROFILES)
    core.set_limits(SimLimits(control_period=0.2, max_force=2.0, max_torque=0.5))
    core.on_inputs(False, '', False, '')
    answer = core.answer(0, 0, 0, State(0.3))
    assert answer.source == MODEL and answer.source_code == 2 and answer.engaged
    assert answer.detail == f'model {model_file}'
    model = ClonedHuman(model_file, 'rotation', control_period=CONTROL_PERIOD)
    assert answer.command == model.act(State(0.3), ['pendulum'])
    assert core.input_status.state == 'ok'
    with pytest.raises(ParameterError, match='input model needs a checkpoint path'):
        from hrc_common.params import checked
        checked(HumanParams(input='model'))
