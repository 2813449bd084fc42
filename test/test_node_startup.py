"""Every node refuses every bad parameter source at once: exit code 2, each reason, no traceback.

The node executables run as ``ros2 run`` starts them, each with several bad sources in one
command line: parameter files that are missing, a list, binary or not YAML (rclpy.init used to
fail on them with a traceback), a misspelt node section and unknown names (used to be ignored
silently), ``-p`` with a misspelt name (the closest known name is the hint).
"""

import subprocess

import pytest

from hrc_common.executables import executable_path

# package, executable, node name, a parameter of the node, the same name misspelt
NODES = [
    ('hrc_sim_node', 'sim_node', 'sim', 'control_period', 'contol_period'),
    ('hrc_agent_node', 'agent_node', 'agent', 'learning_rate', 'lerning_rate'),
    ('hrc_joystick_node', 'human_node', 'human', 'deadzone', 'deadzon'),
    ('hrc_bag', 'recorder_node', 'recorder', 'output_dir', 'output_dri'),
    ('hrc_bag', 'replay_node', 'replay', 'start_offset', 'start_ofset'),
    ('hrc_live', 'display_node', 'display', 'port', 'prot'),
]
IDS = [executable for _, executable, *_ in NODES]


def run(package, executable, ros_args, env=None):
    command = [str(executable_path(package, executable)), '--ros-args', *ros_args]
    return subprocess.run(command, capture_output=True, text=True, timeout=60, env=env)


def assert_refused(result, reasons):
    assert result.returncode == 2, result.stdout + result.stderr
    assert 'Traceback' not in result.stderr, result.stderr
    assert 'parameters rejected (' in result.stderr, result.stderr
    for reason in reasons:
        assert reason in result.stderr, f'{reason!r} missing in:\n{result.stderr}'


@pytest.mark.slow
@pytest.mark.parametrize('package, executable, node, name, typo', NODES, ids=IDS)
def test_unreadable_parameter_files_all_reported(tmp_path, package, executable, node, name,
                                                  typo):
    listed = tmp_path / 'list.yaml'
    listed.write_text('- 1\n- 2\n')
    binary = tmp_path / 'binary.yaml'
    binary.write_bytes(bytes(range(256)) * 4)
    broken = tmp_path / 'broken.yaml'
    broken.write_text(f'{node}:\n  ros__parameters: [\n')
    result = run(package, executable, [
        '--params-file', str(tmp_path / 'missing.yaml'), '--params-file', str(listed),
        '--params-file', str(binary), '--params-file', str(broken), '-p', f'{typo}:=1'])
    assert_refused(result, [
        'missing.yaml: cannot read it: No such file or directory',
        'list.yaml: expected a mapping of node names', 'binary.yaml: not a YAML parameter file',
        'broken.yaml: not YAML at line 3',
        f"-p {typo}: unknown parameter (did you mean '{name}'?)"])


@pytest.mark.parametrize('package, executable, node, name, typo', NODES, ids=IDS)
def test_misspelt_section_and_unknown_names_all_reported(tmp_path, ros_env, package, executable,
                                                         node, name, typo):
    misspelt = tmp_path / 'misspelt.yaml'
    misspelt.write_text(f'{node}x:\n  ros__parameters: {{{name}: 1}}\n')
    unknown = tmp_path / 'unknown.yaml'
    unknown.write_text(f'{node}:\n  ros__parameters:\n    {typo}: 1\n    zzz_qqq: 2\n')
    result = run(package, executable, ['--params-file', str(misspelt), '--params-file',
                                       str(unknown), '-p', f'{typo}:=1'], env=ros_env)
    assert_refused(result, [
        f"misspelt.yaml: section '{node}x' does not name this node (did you mean '{node}'?)",
        f"unknown.yaml: section '{node}': unknown parameter '{typo}' (did you mean '{name}'?)",
        f"unknown.yaml: section '{node}': unknown parameter 'zzz_qqq'",
        f"-p {typo}: unknown parameter (did you mean '{name}'?)"])


@pytest.mark.slow
def test_help_into_a_closed_pipe_is_quiet():
    """`sim_node --help | head -1`: the reader leaves early; no traceback, exit code 0."""
    process = subprocess.Popen([str(executable_path('hrc_sim_node', 'sim_node')), '--help'],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    process.stdout.close()   # before the node has printed anything (it imports for ~1 s)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 0 and b'Traceback' not in stderr, stderr.decode()


@pytest.mark.parametrize('profile_argument, reason', [
    ('profile:=nobody', "profile: 'nobody' is not in "),
    ('profiles_file:=PATH', 'profiles_file: PATH: not valid YAML (line 2, column 1)'),
], ids=['unknown profile', 'broken profiles file'])
def test_the_human_nodes_profile_is_checked_with_the_other_values(tmp_path, profile_argument,
                                                                  reason):
    """A bad profile was reported only once every other value passed, a file not by name."""
    broken = tmp_path / 'profiles.yaml'
    broken.write_text('profiles: [1\n')
    result = run('hrc_joystick_node', 'human_node', [
        '-p', 'deadzone:=5.0', '-p', profile_argument.replace('PATH', str(broken))])
    assert_refused(result, ['parameters rejected (2 reasons)', 'deadzone: ',
                            reason.replace('PATH', str(broken))])
