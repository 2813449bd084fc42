"""hrc_common.params: documented dataclass parameters, validation, YAML, ROS declaration."""

from dataclasses import dataclass

import pytest

from hrc_common.params import (as_dict, checked, declare_parameters, describe, from_dict,
                               load_yaml, param, ParameterError, validate, with_overrides)


@dataclass
class ExampleParams:
    """Parameters of a made-up node."""

    mode: str = param('lockstep', 'Clock mode', choices=('lockstep', 'realtime'))
    period: float = param(0.2, 'Control period (s)', low=0.01, high=1.0)
    episodes: int = param(3, 'Episodes to run', low=0, high=1000)
    verbose: bool = param(False, 'Log every step')
    actors: list = param(['robot', 'human'], 'Actors to wait for', choices=('robot', 'human'))

    def check(self):
        """Cross-field condition: realtime needs a period of at least 0.05 s."""
        if self.mode == 'realtime' and self.period < 0.05:
            return ['period: realtime mode needs at least 0.05 s']
        return []


def test_defaults_are_valid_and_lists_not_shared():
    first, second = ExampleParams(), ExampleParams()
    assert validate(first) == []
    first.actors.append('human')
    assert second.actors == ['robot', 'human']


@pytest.mark.parametrize('overrides, reason', [
    ({'mode': 'fast'}, "mode: 'fast' is not one of ['lockstep', 'realtime']"),
    ({'period': 2.0}, 'period: 2.0 is above the maximum 1.0'),
    ({'period': float('nan')}, 'period: must be finite'),
    ({'episodes': -1}, 'episodes: -1 is below the minimum 0'),
    ({'episodes': 1.5}, 'episodes: expected an integer'),
    ({'verbose': 'yes'}, 'verbose: expected a boolean'),
    ({'actors': ['robot', 'dog']}, "actors: ['dog'] not among"),
    ({'mode': 'realtime', 'period': 0.02}, 'realtime mode needs at least 0.05 s'),
])
def test_bad_values_are_rejected_with_reason(overrides, reason):
    with pytest.raises(ParameterError, match=None) as error:
        from_dict(ExampleParams, overrides)
    assert reason in str(error.value)


def test_every_reason_is_reported_at_once():
    with pytest.raises(ParameterError) as error:
        checked(ExampleParams(period=5.0, episodes=-3))
    assert 'period' in str(error.value) and 'episodes' in str(error.value)


def test_a_cross_field_reason_shows_beside_the_field_reasons():
    # A check() reason (e.g. the agent's session id) only showed once every single
    # field was fixed; now all at once.
    reasons = validate(ExampleParams(mode='realtime', period=0.02, episodes=-3))
    assert 'episodes: -3 is below the minimum 0' in reasons
    assert 'period: realtime mode needs at least 0.05 s' in reasons


def test_a_check_that_cannot_run_on_bad_values_adds_nothing():
    reasons = validate(ExampleParams(mode='realtime', period='fast'))
    assert reasons and all('period' in reason for reason in reasons), reasons


def test_unknown_keys_are_an_error_and_ints_become_floats():
    with pytest.raises(ParameterError, match="unknown parameter 'perod' "
                                             r"\(did you mean 'period'\?\)"):
        from_dict(ExampleParams, {'perod': 0.3})
    assert from_dict(ExampleParams, {'period': 1}).period == 1.0
    assert with_overrides(ExampleParams(), episodes=7).episodes == 7
    assert as_dict(ExampleParams())['mode'] == 'lockstep'


def test_load_yaml_reads_the_node_section(tmp_path):
    path = tmp_path / 'example.yaml'
    path.write_text('example:\n  ros__parameters:\n    period: 0.5\n    actors: [robot]\n'
                    'other:\n  ros__parameters:\n    period: 0.9\n')
    loaded = load_yaml(ExampleParams, path, 'example')
    assert loaded.period == 0.5 and loaded.actors == ['robot']


def test_describe_lists_defaults_bounds_and_docs():
    text = describe(ExampleParams)
    assert 'period (default 0.2) [0.01, 1.0]' in text
    assert 'Control period (s)' in text
    assert '{lockstep, realtime}' in text


def test_declare_parameters_on_a_real_node(rclpy_context):
    import rclpy
    from rclpy.parameter import Parameter

    node = rclpy.create_node('example', context=rclpy_context,
                             parameter_overrides=[Parameter('period', value=0.5)])
    try:
        values = declare_parameters(node, ExampleParams)
        assert values.period == 0.5 and values.actors == ['robot', 'human']
        descriptor = node.describe_parameter('period')
        assert 'Control period' in descriptor.description
        assert descriptor.floating_point_range[0].to_value == 1.0
        assert descriptor.read_only
    finally:
        node.destroy_node()


def test_declare_parameters_rejects_bad_overrides(rclpy_context):
    import rclpy
    from rclpy.parameter import Parameter

    node = rclpy.create_node('example', context=rclpy_context,
                             parameter_overrides=[Parameter('mode', value='warp')])
    try:
        with pytest.raises(ParameterError, match="mode: 'warp' is not one of"):
            declare_parameters(node, ExampleParams)
    finally:
        node.destroy_node()


def test_an_integer_sets_a_float_parameter(rclpy_context):
    import rclpy

    # rcl reads `period:=1` as an integer, which rclpy alone refuses for a float parameter.
    node = rclpy.create_node('example', context=rclpy_context,
                             cli_args=['--ros-args', '-p', 'period:=1', '-p', 'episodes:=2'])
    try:
        values = declare_parameters(node, ExampleParams)
        assert values.period == 1.0 and isinstance(values.period, float)
        assert node.get_parameter('period').value == 1.0 and values.episodes == 2
    finally:
        node.destroy_node()


def test_empty_list_override_means_empty_list(rclpy_context):
    import rclpy

    # As given on the command line (-p actors:=[]), rcl reads it without an element type.
    node = rclpy.create_node('example', context=rclpy_context,
                             cli_args=['--ros-args', '-p', 'actors:=[]'])
    try:
        assert declare_parameters(node, ExampleParams).actors == []
    finally:
        node.destroy_node()


def test_every_reason_is_listed_even_when_rclpy_refuses_a_range(rclpy_context):
    import rclpy
    from rclpy.parameter import Parameter

    node = rclpy.create_node('example', context=rclpy_context, parameter_overrides=[
        Parameter('period', value=5.0), Parameter('mode', value='warp')])
    try:
        with pytest.raises(ParameterError) as error:
            declare_parameters(node, ExampleParams)
        assert 'period' in str(error.value) and "'warp' is not one of" in str(error.value)
    finally:
        node.destroy_node()


def test_changes_are_checked_and_other_parameters_left_alone(rclpy_context):
    import rclpy
    from rcl_interfaces.msg import ParameterDescriptor
    from rclpy.parameter import Parameter

    @dataclass
    class Tunable:
        """A parameter that may change at run time."""

        gain: float = param(1.0, 'gain', low=0.0, high=10.0, read_only=False)

    node = rclpy.create_node('example', context=rclpy_context)
    try:
        declare_parameters(node, Tunable)
        node.declare_parameter('other', 'x', ParameterDescriptor())
        assert node.set_parameters([Parameter('gain', value=2.0)])[0].successful
        assert not node.set_parameters([Parameter('gain', value=20.0)])[0].successful
        assert node.set_parameters([Parameter('other', value='y')])[0].successful
    finally:
        node.destroy_node()


def test_domain_reservations_are_exclusive():
    from hrc_common.domains import DomainReservation

    first, second = DomainReservation(), DomainReservation()
    try:
        assert first.domain_id != second.domain_id
    finally:
        first.release()
        second.release()


def test_command_line_problems_all_at_once(tmp_path):
    from hrc_common.params_arguments import parse_ros_arguments
    good = tmp_path / 'good.yaml'
    good.write_text('/**:\n  ros__parameters: {period: 0.3}\nns:\n  node:\n'
                    '    ros__parameters: {inner: {deep: 1}}\n')
    shapes = tmp_path / 'shapes.yaml'
    shapes.write_text('a: 3\nb: {ros__parameters: [1]}\nc: {}\nd: {ros__parameters: {}, x: 1}\n')
    text = tmp_path / 'text.yaml'
    text.write_text('just words')
    arguments = parse_ros_arguments([
        'exe', 'user-arg', '-p', 'ignored', '--ros-args', '--params-file', str(good),
        '--params-file', str(shapes), '--params-file', str(text), '-p', 'period:=0.1',
        '-p', 'sim:episodes:=4', '-p', 'novalue', '-r', '__node:=x', '--log-level', 'debug',
        '--disable-rosout-logs', '--what', '--', 'tail', '-p', 'also_ignored',
        '--ros-args', '--params-file'])
    assert [f.path for f in arguments.files] == [str(good), str(shapes)]
    assert arguments.files[0].sections == {'/**': {'period': 0.3}, 'ns/node': {'inner.deep': 1}}
    assert arguments.overrides == [('', 'period'), ('sim', 'episodes')]
    problems = '\n'.join(arguments.problems)
    for reason in ("section 'a' must be a mapping with ros__parameters, got int",
                   'b.ros__parameters must be a mapping of parameter names, got list',
                   "section 'c' has no ros__parameters",
                   "section 'd' has keys ['x'] next to ros__parameters",
                   'text.yaml: expected a mapping of node names',
                   '-p novalue: expected name:=value',
                   "unknown argument '--what'", '--ros-args --params-file: a value must follow'):
        assert reason in problems
    assert len(arguments.problems) == 8


def test_node_problems_name_the_closest_parameter_and_section(tmp_path):
    from hrc_common.params_arguments import (node_parameter_problems, parse_ros_arguments,
                                              section_applies)
    assert section_applies('/**', '/sim') and section_applies('/**/sim', '/ns/sim')
    assert section_applies('sim', '/sim') and section_applies('/*', '/sim')
    assert not section_applies('/ns/sim', '/sim') and not section_applies('simm', '/sim')
    shared = tmp_path / 'shared.yaml'
    shared.write_text('sim:\n  ros__parameters: {perod: 1, use_sim_time: true, '
                      'qos_overrides: {/t: {publisher: {depth: 3}}}}\n'
                      'agent:\n  ros__parameters: {anything: 1}\n'
                      'simm:\n  ros__parameters: {period: 1}\n')
    elsewhere = tmp_path / 'elsewhere.yaml'
    elsewhere.write_text('recorder:\n  ros__parameters: {period: 1}\n')
    arguments = parse_ros_arguments(['exe', '--ros-args', '--params-file', str(shared),
                                     '--params-file', str(elsewhere), '-p', 'episods:=2',
                                     '-p', 'agent:whatever:=1', '-p', 'use_sim_time:=true'])
    problems = node_parameter_problems(arguments, 'sim', '/sim', ExampleParams)
    assert problems == [
        f"--params-file {shared}: section 'simm' does not name this node (did you mean 'sim'?)",
        f"--params-file {shared}: section 'sim': unknown parameter 'perod' (did you mean "
        "'period'?)",
        f"--params-file {elsewhere}: no section for node 'sim' (sections: ['recorder'], "
        "expected sim: or /**:)",
        "-p episods: unknown parameter (did you mean 'episodes'?)"]
