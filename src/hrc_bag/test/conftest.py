"""Fixtures of the hrc_bag tests: a node in the test's context, topics of the test's own.

(``rosbags_typestore``, the hrc types for rosbags, comes from the top-level conftest.py.)
"""

import itertools
import os

from hrc_bag.recorder_params import DEFAULT_TOPICS
import pytest

_PREFIXES = itertools.count()


class Isolation:
    """A topic prefix of the test's own, and the remap arguments that move nodes onto it.

    Test runs of other packages may share a ROS domain id with this test on a busy machine; a
    prefix keeps their /hrc traffic out of this test's recordings and listeners.
    """

    def __init__(self):
        self.prefix = f'/t{os.getpid()}_{next(_PREFIXES)}'
        self.ros_args = []
        for topic in DEFAULT_TOPICS + ['/clock']:
            self.ros_args += ['-r', f'{topic}:={self.prefix}{topic}']

    def name(self, topic: str) -> str:
        """Return the prefixed name of ``topic``."""
        return self.prefix + topic


@pytest.fixture
def isolation():
    """Give the test its own topic prefix (see Isolation)."""
    return Isolation()


@pytest.fixture
def test_node(rclpy_context):
    """Give a node in the test's own context (destroyed after the test)."""
    from rclpy.node import Node

    node = Node('hrc_bag_test', context=rclpy_context)
    yield node
    node.destroy_node()
