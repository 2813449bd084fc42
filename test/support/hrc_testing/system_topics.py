"""Check that a session folder shows the system as ROS tools expect it.

/joint_states: one per period's state, stamped as the state, with the state's values;
/robot_description: the URDF the sim loads, once at the start of every episode file (read
with the ``mcap`` library file by file, the way a viewer opens one file).
"""

import pathlib
import xml.etree.ElementTree as ElementTree

from mcap.reader import make_reader
from rclpy.serialization import deserialize_message
from std_msgs.msg import String

JOINTS = ['slide', 'hinge', 'roll']     # prismatic m, revolute rad, prismatic m


def _stamp(message) -> tuple:
    return message.header.stamp.sec, message.header.stamp.nanosec


def check_the_system_is_recorded(folder, bag: dict) -> None:
    """Assert the joint states and the URDF of ``folder`` (``bag``: rosbags' decoded topics)."""
    states = {_stamp(state): state for state in bag['/hrc/state']}
    joints = bag['/joint_states']
    assert len(joints) == len(states) == len(bag['/hrc/state'])
    for joint in joints:
        state = states[_stamp(joint)]
        assert list(joint.name) == JOINTS
        assert list(joint.position) == [state.slider_position, state.pendulum_angle,
                                        state.ball_position]
        assert list(joint.velocity) == [state.slider_velocity, state.pendulum_angular_velocity,
                                        state.ball_velocity]
    files = sorted(pathlib.Path(folder).glob('*_episode*.mcap'))
    assert files
    for path in files:
        with open(path, 'rb') as stream:
            found = [message.data for _, _, message in
                     make_reader(stream).iter_messages(topics=['/robot_description'])]
        assert len(found) == 1, (path.name, len(found))
        robot = ElementTree.fromstring(deserialize_message(found[0], String).data)
        movable = [joint.get('name') for joint in robot.iter('joint')
                   if joint.get('type') != 'fixed']
        assert movable == JOINTS, (path.name, movable)
