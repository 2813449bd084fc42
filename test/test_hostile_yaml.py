"""Hostile YAML handed to the command lines: one line with the file and the reason, no traceback.

20,000 nested brackets used to end in a RecursionError traceback (``hrc session --params``, a
node's ``--params-file``, ``hrc study``, ``hrc tree``, ``--set``); a 5,000-digit integer in a
ValueError from Python's integer-string limit; a study's subjects file that is not YAML in a
traceback of ``hrc study``. Each is refused by hrc_common.bounded_yaml before it is built.
"""

import subprocess

import pytest

from hrc_common.executables import executable_path

DEEP = '[' * 20000 + ']' * 20000
LONG_INTEGER = 'agent:\n  ros__parameters:\n    seed: ' + '9' * 5000 + '\n'
LAUGHS = 'l0: &l0 [ha, ha]\n' + ''.join(
    f'l{level}: &l{level} [*l{level - 1}, *l{level - 1}]\n' for level in range(1, 41))
DEEP_REASON = 'line 1, column 65: nested more than 64 levels deep'


@pytest.fixture
def hostile(tmp_path):
    """Write the hostile files; return {name: path}."""
    files = {'deep': DEEP, 'integer': LONG_INTEGER, 'laughs': LAUGHS}
    for name, text in files.items():
        (tmp_path / f'{name}.yaml').write_text(text)
    return {name: str(tmp_path / f'{name}.yaml') for name in files}


def run(package, executable, *arguments):
    command = [str(executable_path(package, executable)), *arguments]
    return subprocess.run(command, capture_output=True, text=True, timeout=120)


def assert_one_line_refusal(result, code, reason):
    assert result.returncode == code, result.stdout + result.stderr
    assert 'Traceback' not in result.stderr, result.stderr
    errors = [line for line in result.stderr.splitlines() if reason in line]
    assert errors, result.stderr
    assert all(len(line) < 300 for line in errors), errors


@pytest.mark.parametrize('name, reason', [
    ('deep', DEEP_REASON),
    ('integer', 'line 3, column 11: an integer of 5000 digits'),
    ('laughs', 'values with its aliases (*name) expanded'),
])
def test_hrc_session_refuses_a_hostile_params_file(hostile, name, reason):
    result = run('hrc_bringup', 'hrc', 'session', '--params', hostile[name], '--no-record')
    assert_one_line_refusal(result, 2, f'--params {hostile[name]}: ')
    assert reason in result.stderr, result.stderr


def test_hrc_session_refuses_a_hostile_set_value():
    result = run('hrc_bringup', 'hrc', 'session', '--set', 'agent.seed=' + '[' * 5000)
    assert_one_line_refusal(result, 2, '--set agent.seed (line 1): nested more than 64')


def test_a_node_refuses_hostile_parameter_files_with_every_reason(hostile):
    result = run('hrc_agent_node', 'agent_node', '--ros-args', '--params-file', hostile['deep'],
                 '--params-file', hostile['integer'], '--params-file', hostile['laughs'])
    assert_one_line_refusal(result, 2, 'parameters rejected (3 reasons)')
    assert f'--params-file {hostile["deep"]}: not YAML at {DEEP_REASON}' in result.stderr
    assert 'an integer of 5000 digits' in result.stderr
    assert 'values with its aliases (*name) expanded' in result.stderr


@pytest.mark.parametrize('content', [DEEP, '- id: [unclosed\n'], ids=['deep', 'not YAML'])
def test_hrc_study_refuses_a_broken_subjects_file(tmp_path, content):
    (tmp_path / 'subjects.yaml').write_text(content)
    for verb in (['index'], ['register', 'P01', '--consent', 'yes']):
        result = run('hrc_bringup', 'hrc', 'study', *verb, '--study-dir', str(tmp_path))
        assert_one_line_refusal(result, 2, f'study: {tmp_path / "subjects.yaml"}: not readable '
                                'as YAML (line ')
    assert (tmp_path / 'subjects.yaml').read_text() == content      # nothing overwritten


def test_hrc_tree_refuses_a_hostile_tree_file(hostile):
    result = run('hrc_bringup', 'hrc', 'tree', '--tree', hostile['deep'])
    assert_one_line_refusal(result, 1, f'task tree file {hostile["deep"]} is not valid YAML '
                            f'text: {DEEP_REASON}')
