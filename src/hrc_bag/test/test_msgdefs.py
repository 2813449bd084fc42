"""Schemas built from the installed .msg files decode what rclpy serializes."""

from geometry_msgs.msg import WrenchStamped
from hrc_msgs.msg import AgentStep, EpisodeSummary, HumanAction, SessionStatus, TaskState
from mcap.records import Schema
from mcap_ros2.decoder import DecoderFactory
import pytest
from rclpy.serialization import serialize_message

from hrc_bag import msgdefs


def test_dependencies_are_appended_once_after_separators():
    text = msgdefs.full_definition('geometry_msgs/msg/WrenchStamped')
    sections = text.split('\n' + msgdefs.SEPARATOR + '\n')
    headers = [section.splitlines()[0] for section in sections[1:]]
    # Wrench -> Vector3 (once, although force and torque both use it); Header -> Time
    assert sorted(headers) == ['MSG: builtin_interfaces/Time', 'MSG: geometry_msgs/Vector3',
                               'MSG: geometry_msgs/Wrench', 'MSG: std_msgs/Header']
    assert sections[0] == msgdefs.message_text('geometry_msgs/msg/WrenchStamped')


def test_field_types_skip_primitives_comments_arrays_and_constants():
    text = ('uint8 DOF=1  # constant\n# std_msgs/Header in a comment\nstring<=5 name\n'
            'float64[3] values\nPoint[] points\nstd_msgs/Header header\nwstring other\n')
    assert msgdefs.field_types(text, 'geometry_msgs') == ['geometry_msgs/Point',
                                                         'std_msgs/Header']


def test_bad_and_unknown_type_names_are_reported():
    with pytest.raises(ValueError):
        msgdefs.split_type_name('TaskState')
    with pytest.raises(msgdefs.DefinitionNotFound):
        msgdefs.message_text('no_such_package/msg/Nothing')


def _filled_messages():
    state = TaskState(episode=7, step=3, slider_position=0.05, pendulum_angle=-0.2,
                      ball_position=0.11, truncated=True)
    state.header.stamp.sec = 12
    state.header.frame_id = 'world'
    wrench = WrenchStamped()
    wrench.wrench.force.z = 4.5
    wrench.wrench.torque.x = -1.25
    return [
        state, wrench,
        HumanAction(episode=7, step=3, command=-0.5, dof=1, source=2, source_detail='novice',
                    engaged=True),
        SessionStatus(session_id='s', case_id=4, strategy='level_guided',
                      robot_subtasks=['slider', 'pendulum'], phase=2),
        EpisodeSummary(session_id='s', episode=7, slider_error=0.01, total_error=0.3,
                       human_involved=True, evaluation=True),
        AgentStep(episode=7, step=3, action=0.25, subtask_ids=['slider', 'ball'],
                  reward_components=[0.5, 0.25], reward=0.75, deterministic=True),
    ]


@pytest.mark.parametrize('message', _filled_messages(), ids=lambda m: type(m).__name__)
def test_schema_decodes_rclpy_serialized_bytes(message):
    type_name = f'{type(message).__module__.split(".")[0]}/msg/{type(message).__name__}'
    schema = Schema(id=1, name=type_name, encoding='ros2msg',
                    data=msgdefs.full_definition(type_name).encode())
    decoded = DecoderFactory().decoder_for('cdr', schema)(serialize_message(message))
    for name in message.get_fields_and_field_types():
        expected = getattr(message, name)
        actual = getattr(decoded, name)
        if hasattr(expected, 'get_fields_and_field_types'):
            continue
        if isinstance(actual, list) or hasattr(expected, 'tolist'):
            actual, expected = list(actual), list(expected)
        assert actual == expected, name
    if isinstance(message, WrenchStamped):
        assert decoded.wrench.force.z == 4.5 and decoded.wrench.torque.x == -1.25


def test_rosbags_parses_the_concatenated_schema():
    from rosbags.typesys import get_types_from_msg

    types = get_types_from_msg(msgdefs.full_definition('hrc_msgs/msg/TaskState'),
                               'hrc_msgs/msg/TaskState')
    assert 'hrc_msgs/msg/TaskState' in types
    assert 'std_msgs/msg/Header' in types
    fields = [name for name, _ in types['hrc_msgs/msg/TaskState'][1]]
    assert fields[:3] == ['header', 'episode', 'step']
