"""The in-process engine without ROS.

No rclpy, picklable for process pools and Ray, bags the report reads, the graph's QoS
metadata, bad input refused with every reason.
"""

import dataclasses
import pickle
import subprocess
import sys
import textwrap

from hrc_common.session_plan import SessionSettings
from hrc_common.executables import executable_path
from hrc_engine.engine import compose_parameters, EngineConfig, OFFERED_QOS, run_session
from hrc_engine.inprocess_session import main, parse_args
from hrc_testing.system_topics import check_the_system_is_recorded
import pytest

SHORT = {'sim.episode_duration': 2.0, 'agent.horizon': 20, 'agent.minibatch_size': 10}


def short_config(tmp_path, checkpoints=True, **fields):
    """Return the config of a tiny session (10 steps per episode) under tmp_path."""
    values = dict(case=1, seed=3, training_episodes=2, evaluation_episodes=1,
                  session_id='tiny', bags_dir=str(tmp_path / 'bags'),
                  runs_dir=str(tmp_path / 'runs'), overrides=dict(SHORT))
    values.update(fields)
    return EngineConfig(SessionSettings(**values), checkpoints=checkpoints)


@pytest.mark.slow
def test_a_session_runs_without_rclpy_and_its_result_pickles(tmp_path):
    script = textwrap.dedent(f"""
        import pickle, sys
        sys.modules['rclpy'] = None          # any import of rclpy now fails
        from hrc_common.session_plan import SessionSettings
        from hrc_engine.engine import EngineConfig, run_session
        config = EngineConfig(SessionSettings(
            case=1, seed=3, training_episodes=2, evaluation_episodes=1, session_id='tiny',
            bags_dir={str(tmp_path / 'bags')!r}, runs_dir={str(tmp_path / 'runs')!r},
            overrides={SHORT!r}))
        result = run_session(pickle.loads(pickle.dumps(config)))
        sys.stdout.buffer.write(pickle.dumps(result))
    """)
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, timeout=120)
    assert done.returncode == 0, done.stderr.decode()
    result = pickle.loads(done.stdout)
    assert (result.training_episodes, len(result.episodes), result.steps) == (2, 3, 30)
    assert [episode['evaluation'] for episode in result.episodes] == [False, False, True]
    assert result.evaluation['episodes'] == 1 and result.counters == {}
    names = sorted(path.name for path in (tmp_path / 'bags' / 'tiny').iterdir())
    assert names == ['metadata.yaml', 'tiny_end.mcap', 'tiny_episode0001.mcap',
                     'tiny_episode0002.mcap', 'tiny_episode0003.mcap']
    assert (tmp_path / 'runs' / 'checkpoints' / 'tiny' / 'final.pt').is_file()


def test_the_same_seed_gives_the_same_session_and_another_seed_another(tmp_path):
    first = run_session(short_config(tmp_path / 'a', record=False, checkpoints=False))
    again = run_session(short_config(tmp_path / 'b', record=False, checkpoints=False))
    other = run_session(short_config(tmp_path / 'c', seed=4, record=False, checkpoints=False))
    assert first.episodes == again.episodes and first.evaluation == again.evaluation
    assert first.episodes != other.episodes


@pytest.mark.slow
def test_the_bags_carry_the_graphs_qos_and_the_report_reads_them(tmp_path, read_rosbag):
    from hrc_bag.format import offered_profile
    from hrc_common import qos
    import yaml

    result = run_session(short_config(tmp_path))
    metadata = yaml.safe_load((tmp_path / 'bags' / 'tiny' / 'metadata.yaml').read_text())
    topics = {entry['topic_metadata']['name']: entry['topic_metadata'] for entry in
              metadata['rosbag2_bagfile_information']['topics_with_message_count']}
    assert set(topics) == set(OFFERED_QOS)
    for topic, profile in ((('/hrc/state', qos.STATE_QOS)), ('/hrc/session', qos.SESSION_QOS),
                           ('/hrc/robot/cmd_wrench', qos.COMMAND_QOS)):
        expected = offered_profile(profile.reliability.name == 'RELIABLE',
                                   profile.durability.name == 'TRANSIENT_LOCAL',
                                   int(profile.deadline.nanoseconds))
        assert topics[topic]['offered_qos_profiles'] == [expected], topic
        assert topics[topic]['type_description_hash'].startswith('RIHS01_')
    bag = read_rosbag(tmp_path / 'bags' / 'tiny')
    assert len(bag['/hrc/state']) == 3 * 11 and len(bag['/hrc/agent/step']) == 30
    check_the_system_is_recorded(tmp_path / 'bags' / 'tiny', bag)     # as the graph's bags
    report = subprocess.run([str(executable_path('hrc_bringup', 'hrc')),
                             'bag', 'report', result.bag_dir,
                             '--out', str(tmp_path / 'report')],
                            capture_output=True, text=True, timeout=120)
    assert report.returncode == 0, report.stdout + report.stderr
    table = (tmp_path / 'report' / 'table2.md').read_text()
    assert '| 1 | task first | translation | 1 |' in table, table     # case 1, one seed


def test_offered_qos_table_matches_the_contract():
    from hrc_common import qos, topics
    contract = {topics.STATE: qos.STATE_QOS, topics.ROBOT_CMD_WRENCH: qos.COMMAND_QOS,
                topics.HUMAN_CMD_WRENCH: qos.COMMAND_QOS,
                topics.HUMAN_ACTION: qos.HUMAN_ACTION_QOS, topics.SESSION: qos.SESSION_QOS,
                topics.EPISODE: qos.EPISODE_QOS, topics.AGENT_STEP: qos.AGENT_STEP_QOS,
                topics.ROBOT_DESCRIPTION: qos.OF_TOPIC[topics.ROBOT_DESCRIPTION],
                topics.JOINT_STATES: qos.OF_TOPIC[topics.JOINT_STATES]}
    assert set(contract) == set(OFFERED_QOS)
    for topic, profile in contract.items():
        deadline = profile.deadline.nanoseconds
        assert OFFERED_QOS[topic] == (profile.reliability.name == 'RELIABLE',
                                      profile.durability.name == 'TRANSIENT_LOCAL',
                                      0 if deadline in (0, 2 ** 63 - 1) else deadline), topic


@pytest.mark.parametrize('argv, reason', [
    (['--set', 'sim.max_force'], 'expected node.parameter=value'),
    (['--set', 'sim.control_period=-1', '--set', 'agent.horizon=0'], 'control_period'),
    (['--case', '9'], 'case'),
])
def test_bad_input_exits_2_with_the_reason(argv, reason, tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        code = main(['--bags-dir', str(tmp_path), '--runs-dir', str(tmp_path), *argv])
        raise SystemExit(code)
    assert exit_info.value.code == 2
    assert reason in capsys.readouterr().err


def test_the_engine_takes_the_one_session_configuration():
    """EngineConfig keeps the engine's own run options beside a SessionSettings, no copy."""
    own = {field.name for field in dataclasses.fields(EngineConfig)}
    assert own == {'settings', 'checkpoints', 'params_dir', 'parameters', 'quiet'}
    assert not own & {field.name for field in dataclasses.fields(SessionSettings)}
    config, as_json = parse_args(['--case', '3', '--seed', '4', '--profile', 'novice',
                                  '--set', 'sim.episode_duration=2', '--no-checkpoints'])
    assert config.settings == SessionSettings(case=3, seed=4, human_profile='novice',
                                              overrides={'sim.episode_duration': 2})
    assert not config.checkpoints and not as_json
    settings, parameters = compose_parameters(config)
    assert settings.session_id.startswith('case3-seed4-') and not config.settings.session_id
    assert parameters['human']['profile'] == 'novice' and parameters['sim']['seed'] == 4
    with pytest.raises(ValueError, match='lockstep only'):
        compose_parameters(EngineConfig(SessionSettings(mode='realtime')))


@pytest.mark.parametrize('actors', [['robot'], ['human']])
def test_the_engine_refuses_a_sim_that_waits_for_one_actor(tmp_path, actors, capsys):
    """One expected actor is a race in the graph (the other's command applied only if first)."""
    config = short_config(tmp_path, overrides=dict(SHORT, **{'sim.expected_actors': actors}))
    with pytest.raises(ValueError, match=r'sim.expected_actors .*waits for both actors'):
        run_session(config)
    assert main(['--set', f'sim.expected_actors=[{actors[0]}]', '--no-record',
                 '--runs-dir', str(tmp_path / 'runs')]) == 2
    assert 'use --engine graph' in capsys.readouterr().err
