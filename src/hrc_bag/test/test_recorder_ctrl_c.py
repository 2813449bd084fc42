"""Ctrl-C on a recorder started by hand: its last lines, and no rosout error beside them.

rclpy's signal handler shuts the context down before the node closes, so the recorder's last
line ("N messages recorded in M files") used to come with "Failed to publish log message to
rosout: publisher's context is invalid".
"""

from diagnostic_msgs.msg import DiagnosticArray
import rclpy
from rclpy.executors import SingleThreadedExecutor

from hrc_testing.nodes import wait_for


def test_ctrl_c_says_what_was_recorded_without_a_rosout_error(start_node, tmp_path,
                                                              rclpy_context):
    recorder = start_node('hrc_bag', 'recorder_node', parameters={'output_dir': str(tmp_path)})
    # The recorder's first /diagnostics: its executor runs its timers, so the node is made and
    # spinning (its "recording <topic>" lines are logged while it is still being made, and a
    # Ctrl-C then stops it before there is a node to close or anything to count).
    node = rclpy.create_node('ctrl_c_test', context=rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    statuses = []
    node.create_subscription(DiagnosticArray, '/diagnostics', lambda message: statuses.extend(
        status.name for status in message.status), 10)
    assert wait_for(lambda: 'recorder: writing' in statuses, 60,
                    spin=lambda: executor.spin_once(0.05)), recorder.output
    assert recorder.stop(timeout=60) == 0, recorder.output
    assert '[INFO] [recorder]: 0 messages recorded in 0 files; process CPU ' in \
        recorder.output, recorder.output
    assert 'Failed to publish log message to rosout' not in recorder.output
    assert 'Traceback' not in recorder.output
