"""The ``hrc`` command (hrc_bringup.cli): verbs, help with an example, refusals with reasons.

In-process calls of ``cli.main`` (no ROS graph); one subprocess test runs the installed ``hrc``
as ``ros2 run hrc_bringup hrc`` starts it.
"""

import argparse
import subprocess

from hrc_testing.bag_traffic import record_in_process, strategy_plan
from hrc_bringup import bag_info, cli
from hrc_common.executables import executable_path
import pytest


def run(capsys, *argv) -> tuple:
    """Return (exit code, stdout, stderr) of ``hrc argv``."""
    code = cli.main(list(argv))
    printed = capsys.readouterr()
    return code, printed.out, printed.err


def test_hrc_help_lists_every_verb(capsys):
    code, out, _ = run(capsys, '--help')
    assert code == 0
    for verb in cli.VERBS:
        assert f'  {verb.name} ' in out, verb.name
    for name in ('session', 'experiment', 'bag report', 'bag replay', 'bag info', 'results',
                 'study', 'operator', 'partners clone', 'partners crossplay',
                 'partners advisor', 'tree'):
        assert name in {verb.name for verb in cli.VERBS}
    assert all(len(line) <= cli.USAGE_WIDTH for line in out.splitlines()), out


@pytest.mark.parametrize('verb', [verb.name for verb in cli.VERBS])
def test_every_verb_has_help_with_an_example(capsys, verb):
    code, out, err = run(capsys, *verb.split(), '--help')
    assert code == 0, err
    assert 'usage:' in out
    example = next(v.example for v in cli.VERBS if v.name == verb)
    assert out.rstrip().endswith(f'example:\n  {example}'), out
    assert example.startswith(f'hrc {verb} ')


def undocumented_flags(parser: argparse.ArgumentParser) -> list:
    """Return the flags of ``parser`` and its sub-parsers that have no help text."""
    missing = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                missing += undocumented_flags(sub)
        elif not action.help:
            missing.append(f'{parser.prog} {"/".join(action.option_strings) or action.dest}')
    return missing


@pytest.mark.parametrize('argv', [verb.name.split() for verb in cli.VERBS]
                         + [['session', '--engine', 'inprocess']], ids=' '.join)
def test_every_flag_of_every_verb_has_help(monkeypatch, argv):
    parsers = []

    def capture(parser, args=None, namespace=None):
        parsers.append(parser)
        raise SystemExit(0)
    monkeypatch.setattr(argparse.ArgumentParser, 'parse_known_args', capture)
    cli.main([*argv, '--help'])
    assert parsers, argv
    assert [flag for parser in parsers for flag in undocumented_flags(parser)] == []


@pytest.mark.parametrize('group', ['bag', 'partners', 'joystick'])
def test_a_group_verbs_help_lists_its_verbs_and_exits_0(capsys, group):
    code, out, err = run(capsys, group, '--help')
    assert code == 0 and err == ''
    assert out.startswith(f'usage: hrc {group} <verb>')
    names = [verb.name for verb in cli.VERBS if verb.words[0] == group]
    assert names and all(f'  {name} ' in out for name in names), out
    assert '  session ' not in out and '  results ' not in out


def test_no_verb_unknown_verb_and_a_group_without_its_verb_exit_2_with_the_reason(capsys):
    code, out, err = run(capsys)
    assert code == 2 and 'usage: hrc <verb>' in err
    code, _, err = run(capsys, 'sesion', '--case', '2')
    assert code == 2
    assert "unknown verb 'sesion' (did you mean 'session'?)" in err
    code, _, err = run(capsys, 'bag')
    assert code == 2 and "'bag' needs one of: report, replay, info (none given)" in err
    code, _, err = run(capsys, 'partners', 'klone')
    assert code == 2 and "'klone' is not one of them" in err
    assert 'Traceback' not in err


def test_take_engine_and_study_dir_first():
    assert cli.take_engine(['--case', '2', '--engine', 'inprocess', '--seed', '1']) == (
        'inprocess', ['--case', '2', '--seed', '1'], [])
    assert cli.take_engine(['--engine=graph']) == ('graph', [], [])
    assert cli.take_engine(['--case', '2']) == ('graph', ['--case', '2'], [])
    engine, _, problems = cli.take_engine(['--engine', 'fast'])
    assert problems == ["--engine must be one of graph, inprocess, got 'fast'"]
    assert cli.take_engine(['--engine'])[2] == ['--engine needs a value']
    assert cli.study_dir_first(['register', 'P07', '--study-dir', 's', '--consent', 'yes']) == [
        '--study-dir', 's', 'register', 'P07', '--consent', 'yes']
    assert cli.study_dir_first(['index', '--study-dir=s']) == ['--study-dir=s', 'index']


def test_session_engine_inprocess_refuses_what_only_the_graph_does_every_reason(capsys):
    code, _, err = run(capsys, 'session', '--engine', 'inprocess', '--human', 'joy', '--mode',
                       'realtime', '--episodes', '-1')
    assert code == 2
    assert '--human joy: the in-process engine runs the simulated human, a cloned model or a ' \
        'scripted stick only' in err
    assert '--mode realtime: the in-process engine runs lockstep only' in err
    assert '--episodes must be >= 0' in err
    assert 'Traceback' not in err
    code, _, err = run(capsys, 'session', '--engine', 'warp')
    assert code == 2 and 'hrc session: --engine must be one of graph, inprocess' in err


def test_session_human_model_needs_its_file(capsys):
    code, _, err = run(capsys, 'session', '--human', 'model', '--case', '2')
    assert code == 2
    assert '--human model needs --set human.model_file=PATH' in err


def test_study_takes_study_dir_after_its_command(tmp_path, capsys):
    code, out, err = run(capsys, 'study', 'register', 'P07', '--consent', 'yes',
                         '--study-dir', str(tmp_path))
    assert code == 0, err
    assert (tmp_path / 'subjects.yaml').is_file() or any(tmp_path.iterdir())


@pytest.fixture
def session_bag(tmp_path):
    plan = strategy_plan('learn_together', 1, 0, 1)
    record_in_process(tmp_path / 'bags', 'demo', 5, 'learn_together', 2, plan, steps=4)
    return tmp_path / 'bags' / 'demo'


def test_bag_info_counts_the_messages_of_a_session(session_bag, capsys):
    code, out, err = run(capsys, 'bag', 'info', str(session_bag))
    assert code == 0, err
    lines = out.splitlines()
    files = sorted(session_bag.glob('*.mcap'))
    assert lines[1].startswith(f'files:     {len(files)} (')
    counts = {line.split()[0]: int(line.split()[1]) for line in lines
              if line.startswith('  /')}
    # the same numbers as reading every message of every file
    expected = {}
    for file in files:
        for message in bag_info.scan_file(file).messages:
            expected[message.topic] = expected.get(message.topic, 0) + 1
    assert counts == expected
    assert lines[2] == f'messages:  {sum(expected.values())}'


def test_bag_info_gives_every_reason_a_path_is_not_a_bag(tmp_path, capsys):
    (tmp_path / 'empty.mcap').write_bytes(b'')
    code, _, err = run(capsys, 'bag', 'info', str(tmp_path / 'missing'),
                       str(tmp_path / 'empty.mcap'))
    assert code == 2
    assert 'missing: does not exist' in err and 'is empty, not an MCAP file' in err


def test_bag_replay_flags_become_the_replay_nodes_parameters(session_bag):
    arguments = bag_info.replay_arguments([str(session_bag), '--rate', '2', '--loop',
                                           '--topics', '/hrc/state', '--start-offset', '1.5'])
    assert arguments == ['--ros-args', '-p', f'path:={session_bag.resolve()}', '-p',
                         'rate:=2.0', '-p', 'loop:=true', '-p', "topics:=['/hrc/state']", '-p',
                         'start_offset:=1.5']
    with pytest.raises(SystemExit) as exit_:
        bag_info.replay_arguments([str(session_bag / 'nothing')])
    assert exit_.value.code == 2


@pytest.mark.slow
def test_the_installed_hrc_runs_as_ros2_run_starts_it(tmp_path):
    hrc = str(executable_path('hrc_bringup', 'hrc'))
    result = subprocess.run([hrc, 'tree', '--case', '2'], capture_output=True, text=True,
                            timeout=120, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert 'case 2: responsibility_guided' in result.stdout, result.stdout
    result = subprocess.run([hrc, 'nothing'], capture_output=True, text=True, timeout=60)
    assert result.returncode == 2 and 'Traceback' not in result.stderr


def test_a_partners_first_case_in_the_engine_without_its_pre_training_is_refused(capsys,
                                                                                 tmp_path):
    code, _, err = run(capsys, 'session', '--engine', 'inprocess', '--case', '7', '--episodes',
                       '1', '--no-record', '--runs-dir', str(tmp_path))
    assert code == 2, err
    assert 'case 7: the steps before the person train with a simulated population' in err
    assert 'python -m hrc_partners.partners_first --case 7' in err
    assert 'Traceback' not in err
