"""hrc_common.session_plan: one consistent parameter set per session."""

from dataclasses import fields

import pytest
import yaml

from hrc_common.paths import params_dir
from hrc_common.params import spec_of
from hrc_common.session_plan import (compose, new_session_id, override_arguments,
                                     parse_override, parse_overrides, SessionSettings,
                                     write_session_files)

PARAMS = params_dir()


def test_roles_of_the_six_cases():
    roles = [(compose(SessionSettings(case=case), PARAMS)['sim']['robot_dof'],
              compose(SessionSettings(case=case), PARAMS)['human']['dof']) for case in range(1, 7)]
    assert roles == [('translation', 'rotation'), ('rotation', 'translation')] * 3


def test_compose_makes_the_nodes_agree():
    settings = SessionSettings(case=3, seed=7, session_id='case3-seed7', training_episodes=12,
                               overrides={'agent.learning_rate': 0.0005, 'sim.max_force': 3.0})
    parameters = compose(settings, PARAMS)
    sim, agent, human = parameters['sim'], parameters['agent'], parameters['human']
    assert sim['robot_dof'] == 'translation'
    assert agent['case'] == 3 and agent['max_training_episodes'] == 12
    assert {sim['seed'], agent['seed'], human['seed']} == {7}
    assert agent['learning_rate'] == 0.0005
    # The limits are the sim's alone: the actors read them from the sim at run time, so no
    # other node's parameters repeat them (an override changes the sim, and with it both).
    assert sim['max_force'] == 3.0
    for node in (agent, human):
        assert not {'max_force', 'max_torque', 'control_period'} & set(node)
    assert parameters['recorder']['session_id'] == 'case3-seed7'
    # The first episode waits for the human node's and the recorder's subscriptions.
    assert sorted(agent['wait_for_subscribers']) == ['human', 'recorder']


@pytest.mark.parametrize('settings, reason', [
    (SessionSettings(case=9), 'case must be one of 1..8, got 9'),
    (SessionSettings(mode='fast'), "mode must be 'lockstep' or 'realtime'"),
    (SessionSettings(seed=-1), 'seed must be >= 0'),
    (SessionSettings(overrides={'robot.x': 1}), '--set robot.x: the node must be one of'),
    (SessionSettings(session_id='a/b'), "session id 'a/b' is not valid"),
    (SessionSettings(session_id='../../x'), "session id '../../x' is not valid"),
    (SessionSettings(subject_id='/etc/p'), "subject id '/etc/p' is not valid"),
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
    assert config_path.stat().st_mode & 0o777 == 0o600


def test_every_reason_at_once():
    settings = SessionSettings(case=0, mode='fast', seed=-2, session_id='..', subject_id='a b')
    with pytest.raises(ValueError) as error:
        compose(settings, PARAMS)
    for reason in ('case must be', 'mode must be', 'seed must be', 'session id', 'subject id'):
        assert reason in str(error.value)


def test_an_override_the_session_overrules_is_refused_not_dropped():
    """``--set human.input=script`` used to vanish under the session's own --human sim."""
    settings = SessionSettings(case=2, seed=1, overrides={
        'human.input': 'script', 'agent.seed': 4, 'sim.seed': 1, 'agent.horizon': 256,
        'agent.practice_episodes': 2})
    with pytest.raises(ValueError) as error:
        compose(settings, PARAMS)
    text = str(error.value)
    assert "--set human.input='script': the session sets human.input itself ('sim'); use " \
        '--human' in text
    assert '--set agent.seed=4: the session sets agent.seed itself (1); use --seed' in text
    # the condition's agent never runs a practice instead (that is --practice, before it)
    assert ('--set agent.practice_episodes=2: the session sets agent.practice_episodes itself '
            '(0); use --practice') in text
    assert 'sim.seed' not in text and 'horizon' not in text   # the same value, or not owned
    settings.human_input, settings.overrides = 'script', {'human.input': 'script'}
    assert compose(settings, PARAMS)['human']['input'] == 'script'


def test_the_session_applies_its_learning_configuration_under_the_overrides(tmp_path):
    from hrc_common.session_plan import DEFAULT_LEARNING, load_learning

    defaults = yaml.safe_load((PARAMS / 'agent.yaml').read_text())['agent']['ros__parameters']
    assert DEFAULT_LEARNING == 'sac'
    for name in ('sac', 'ppo', 'paper'):
        learning = load_learning(PARAMS, name)
        agent = compose(SessionSettings(case=2, learning=name), PARAMS)['agent']
        assert {key: agent[key] for key in learning} == learning, name
        assert set(learning) <= set(defaults), name        # only the agent's parameters
    # the default needs no option; --set wins over the configuration
    assert compose(SessionSettings(case=2), PARAMS)['agent']['algorithm'] == 'sac'
    agent = compose(SessionSettings(case=2, overrides={'agent.preset': 'graded'}), PARAMS)['agent']
    assert (agent['algorithm'], agent['preset']) == ('sac', 'graded')
    # --episodes wins over the configuration's episode cap
    assert compose(SessionSettings(case=2, training_episodes=7), PARAMS)['agent'][
        'max_training_episodes'] == 7
    # every session records the configuration's name and its whole content
    settings = SessionSettings(case=2, learning='ppo', session_id='s1')
    _, config_path = write_session_files(settings, compose(settings, PARAMS), tmp_path, PARAMS)
    recorded = yaml.safe_load(config_path.read_text())['learning']
    assert recorded == {'name': 'ppo', 'settings': load_learning(PARAMS, 'ppo')}


def test_an_unknown_learning_configuration_is_refused_with_the_names_there_are(tmp_path):
    with pytest.raises(ValueError) as refused:
        compose(SessionSettings(case=2, learning='fast'), PARAMS)
    assert "learning configuration 'fast' not found" in str(refused.value)
    assert 'there are: paper, partner_aware, ppo, sac' in str(refused.value)
    # a file that is not one agent section is refused with what it holds
    (tmp_path / 'learning').mkdir()
    (tmp_path / 'learning' / 'odd.yaml').write_text('sim:\n  ros__parameters: {seed: 1}\n')
    from hrc_common.session_plan import load_learning
    with pytest.raises(ValueError, match=r"one section, agent: ros__parameters.*\['sim'\]"):
        load_learning(tmp_path, 'odd')


def test_every_setting_is_documented_and_checked_with_every_reason_at_once():
    """The one session configuration: each field carries its description (params.param)."""
    for setting in fields(SessionSettings):
        assert len(spec_of(setting).description) > 15, setting.name
    # types of every field, beside the domain reasons, in one list
    settings = SessionSettings(case=9, record='yes', training_episodes=-3, overrides=['x'],
                               human_profile=3, session_id='a/b')
    reasons = settings.check()
    for expected in ('case must be one of 1..8, got 9', 'record: expected a boolean',
                     'training_episodes: -3 is below the minimum 0',
                     'overrides: expected a mapping', 'human_profile: expected a string',
                     "session id 'a/b' is not valid"):
        assert any(expected in reason for reason in reasons), (expected, reasons)
    assert SessionSettings().check() == []
    # a dict default is copied per instance, as a list default is
    first, second = SessionSettings(), SessionSettings()
    first.overrides['sim.seed'] = 1
    assert second.overrides == {}


def test_overrides_go_back_to_the_command_line_unchanged():
    """The experiment's graph tasks pass the session's overrides as --set texts."""
    overrides = {'sim.episode_duration': 2.0, 'agent.horizon': 20, 'human.profile': 'novice',
                 'sim.expected_actors': ['robot'], 'agent.resume_from': '', 'agent.flag': True,
                 'agent.learning_rate': 0.0003, 'human.script_file': '/tmp/a b: c.csv'}
    arguments = override_arguments(overrides)
    assert arguments[0::2] == ['--set'] * len(overrides)
    assert parse_overrides(arguments[1::2]) == overrides
    assert arguments[1] == 'sim.episode_duration=2.0'


def test_adapt_from_learns_from_each_of_the_persons_episodes_without_judging(tmp_path):
    """--adapt-from: the inherited policy learns from every one of the person's episodes."""
    checkpoint = tmp_path / 'final.pt'
    checkpoint.write_bytes(b'')
    agent = compose(SessionSettings(case=8, adapt_from=str(checkpoint)), PARAMS)['agent']
    assert agent['start_from'] == str(checkpoint) and agent['start_from_judged'] is False
    # three episodes by default (what the held-out protocol measured), and no judging episode
    # falls due before they end
    assert agent['max_training_episodes'] == agent['judging_interval'] == 3
    longer = compose(SessionSettings(case=8, adapt_from=str(checkpoint), training_episodes=5),
                     PARAMS)['agent']
    assert longer['max_training_episodes'] == longer['judging_interval'] == 5
    # a returning person's start judges the inherited policy first, as before
    returning = compose(SessionSettings(case=8, start_from=str(checkpoint)), PARAMS)['agent']
    assert returning['start_from_judged'] is True


def test_adapt_from_is_refused_with_another_start_or_a_judged_start(tmp_path):
    checkpoint = tmp_path / 'final.pt'
    checkpoint.write_bytes(b'')
    settings = SessionSettings(case=8, adapt_from=str(tmp_path / 'missing.pt'),
                               start_from=str(checkpoint),
                               overrides={'agent.start_from_judged': True})
    with pytest.raises(ValueError) as error:
        compose(settings, PARAMS)
    text = str(error.value)
    assert 'cannot be combined with --resume-from or --start-from' in text
    assert f'--adapt-from {tmp_path / "missing.pt"}: no such checkpoint file' in text
    settings.start_from, settings.adapt_from = '', str(checkpoint)
    with pytest.raises(ValueError) as error:
        compose(settings, PARAMS)
    assert ('--set agent.start_from_judged=True: the session sets agent.start_from_judged '
            'itself (False); use --adapt-from') in str(error.value)
