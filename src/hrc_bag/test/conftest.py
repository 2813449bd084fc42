"""Fixtures of the hrc_bag tests: a synthetic publisher node and the hrc types for rosbags."""

import pathlib

import pytest


@pytest.fixture
def test_node(rclpy_context):
    """Give a node in the test's own context (destroyed after the test)."""
    from rclpy.node import Node

    node = Node('hrc_bag_test', context=rclpy_context)
    yield node
    node.destroy_node()


@pytest.fixture(scope='session')
def rosbags_typestore():
    """Return a rosbags typestore of ROS 2 Jazzy plus the installed hrc_msgs types."""
    from ament_index_python.packages import get_package_share_directory
    from rosbags.typesys import get_types_from_msg, get_typestore, Stores

    typestore = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    folder = pathlib.Path(get_package_share_directory('hrc_msgs')) / 'msg'
    for path in sorted(folder.glob('*.msg')):
        types.update(get_types_from_msg(path.read_text(), f'hrc_msgs/msg/{path.stem}'))
    typestore.register(types)
    return typestore
