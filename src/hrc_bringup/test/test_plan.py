"""hrc_bringup.plan: one consistent parameter set per session."""

import pathlib

import pytest
import yaml

from hrc_bringup.plan import (compose, new_session_id, parse_override, robot_dof_of_case,
                              SessionSettings, write_session_files)

PARAMS = pathlib.Path(__file__).resolve().parents[3] / 'params'


def test_roles_of_the_six_cases():
    assert [robot_dof_of_case(case) for case in range(1, 7)] == [
        'translation', 'rotation'] * 3


def test_compose_makes_the_nodes_agree():
    settings = SessionSettings(case=3, seed=7, session_id='case3-seed7', training_episodes=12,
                               overrides={'agent.learning_rate': 0.0005, 'sim.max_force': 3.0})
    parameters = compose(settings, PARAMS)
    sim, agent, human = parameters['sim'], parameters['agent'], parameters['human']
    assert sim['robot_dof'] == 'translation'
    assert agent['case'] == 3 and agent['max_training_episodes'] == 12
    assert {sim['seed'], agent['seed'], human['seed']} == {7}
    assert agent['learning_rate'] == 0.0005
    # The limits are the sim's; the actors take them, overrides included.
    assert agent['max_force'] == human['max_force'] == sim['max_force'] == 3.0
    assert agent['max_torque'] == human['max_torque'] == sim['max_torque']
    assert parameters['recorder']['session_id'] == 'case3-seed7'


@pytest.mark.parametrize('settings, reason', [
    (SessionSettings(case=7), 'case must be 1..6'),
    (SessionSettings(mode='fast'), "mode must be 'lockstep' or 'realtime'"),
    (SessionSettings(seed=-1), 'seed must be >= 0'),
    (SessionSettings(overrides={'robot.x': 1}), '--set robot.x: the node must be one of'),
    (SessionSettings(session_id='a/b'), 'must not contain'),
])
def test_bad_settings_are_rejected(settings, reason):
    with pytest.raises(ValueError, match=None) as error:
        compose(settings, PARAMS)
    assert reason in str(error.value)


def test_parse_override():
    assert parse_override('agent.learning_rate=0.0003') == ('agent', 'learning_rate', 0.0003)
    assert parse_override('sim.expected_actors=[robot]') == ('sim', 'expected_actors', ['robot'])
    with pytest.raises(ValueError, match='expected node.parameter=value'):
        parse_override('learning_rate=1')


def test_session_files(tmp_path):
    settings = SessionSettings(case=2, seed=1, subject_id='P07', notes='first try')
    settings.session_id = new_session_id(settings)
    assert settings.session_id.startswith('case2-seed1-')
    parameters = compose(settings, PARAMS)
    params_path, config_path = write_session_files(settings, parameters, tmp_path)
    written = yaml.safe_load(params_path.read_text())
    assert written['agent']['ros__parameters']['case'] == 2
    config = yaml.safe_load(config_path.read_text())
    assert config['strategy'] == 'responsibility_guided' and config['robot_dof'] == 'rotation'
    assert config['subject_id'] == 'P07' and config['parameters']['sim']['seed'] == 1
