"""params/<node>.yaml are generated from the nodes' dataclasses, and rcl reads them as such."""

from dataclasses import fields
import pathlib

import pytest
import yaml

from hrc_bringup import params_files
from hrc_common.params import default_of
from hrc_common.paths import params_dir
from hrc_common.session_plan import NODES

PARAMS = pathlib.Path(params_dir())
FILES = sorted(params_files.PARAMETER_FILES)


@pytest.mark.parametrize('name', FILES)
def test_each_parameter_file_is_the_one_generated_from_its_dataclass(name):
    expected = params_files.rendered()[name]
    assert (PARAMS / name).read_text() == expected, \
        f'params/{name} differs from its dataclass: run {params_files.COMMAND}'


@pytest.mark.parametrize('name', FILES)
def test_each_file_holds_every_field_with_its_default_and_its_description(name):
    node_name, params_cls = params_files.PARAMETER_FILES[name]
    text = (PARAMS / name).read_text()
    values = yaml.safe_load(text)[node_name]['ros__parameters']
    assert values == {field.name: default_of(field) for field in fields(params_cls)}
    assert all(type(values[field.name]) is type(default_of(field)) for field in fields(params_cls))
    lines = text.splitlines()
    line_of = {line.split(':')[0].strip(): index for index, line in enumerate(lines)
               if line.startswith('    ') and not line.startswith('    #')}
    assert set(line_of) == set(values)
    for field in fields(params_cls):
        assert lines[line_of[field.name] - 1].startswith('    # '), f'{field.name}: no comment'


def test_every_node_file_of_a_session_and_of_params_is_generated():
    assert {file for _, _, file in NODES.values()} <= set(FILES)
    parameter_files = {path.name for path in PARAMS.glob('*.yaml')
                       if any(isinstance(section, dict) and 'ros__parameters' in section
                              for section in (yaml.safe_load(path.read_text()) or {}).values())}
    assert parameter_files == set(FILES)


def test_check_names_a_stale_file_and_the_command_and_write_mends_it(tmp_path, capsys):
    assert params_files.main(['--write', '--params-dir', str(tmp_path)]) == 0
    assert sorted(path.name for path in tmp_path.iterdir()) == FILES
    assert params_files.main(['--check', '--params-dir', str(tmp_path)]) == 0
    stale = tmp_path / 'sim.yaml'
    stale.write_text(stale.read_text().replace('max_force: 2.0', 'max_force: 3.0'))
    (tmp_path / 'display.yaml').unlink()
    capsys.readouterr()
    assert params_files.main(['--check', '--params-dir', str(tmp_path)]) == 1
    errors = capsys.readouterr().err
    assert 'sim.yaml: differs from its dataclass' in errors and 'display.yaml' in errors
    assert params_files.COMMAND in errors and 'agent.yaml' not in errors
    assert params_files.main(['--write', '--params-dir', str(tmp_path)]) == 0
    assert 'wrote sim.yaml, display.yaml' in capsys.readouterr().out
    assert params_files.main(['--check', '--params-dir', str(tmp_path)]) == 0


def test_rcl_reads_each_file_as_the_dataclass_defaults(ros_domain_id):
    # The files are ROS 2 parameter files: rcl's own parser (not PyYAML) gives every value
    # with its type, as `ros2 run ... --ros-args --params-file` does.
    import rclpy
    from rclpy.context import Context
    from rclpy.node import Node

    for name in FILES:
        node_name, params_cls = params_files.PARAMETER_FILES[name]
        context = Context()
        rclpy.init(context=context, domain_id=ros_domain_id,
                   args=['--ros-args', '--params-file', str(PARAMS / name)])
        try:
            node = Node(node_name, context=context,
                        automatically_declare_parameters_from_overrides=True)
            read = {field.name: node.get_parameter(field.name).value
                    for field in fields(params_cls)}
            node.destroy_node()
        finally:
            rclpy.shutdown(context=context)
        for field in fields(params_cls):
            default = default_of(field)
            value = read[field.name]
            if isinstance(default, list):
                value = [] if value is None else list(value)   # [] arrives untyped (NOT_SET)
            assert value == default and type(value) is type(default), (name, field.name, value)
