"""Ctrl-C on a recorder started by hand: its last lines, and no rosout error beside them.

rclpy's signal handler shuts the context down before the node closes, so the recorder's last
line ("N messages recorded in M files") used to come with "Failed to publish log message to
rosout: publisher's context is invalid".
"""

from hrc_bag.recorder_params import DEFAULT_TOPICS
from hrc_testing.nodes import wait_for


def test_ctrl_c_says_what_was_recorded_without_a_rosout_error(start_node, tmp_path):
    recorder = start_node('hrc_bag', 'recorder_node', parameters={'output_dir': str(tmp_path)})
    # every default topic subscribed: the node is past its start and spinning
    assert wait_for(lambda: f'recording {DEFAULT_TOPICS[-1]} ' in recorder.output, 60), \
        recorder.output
    assert recorder.stop(timeout=60) == 0, recorder.output
    assert '[INFO] [recorder]: 0 messages recorded in 0 files; process CPU ' in \
        recorder.output, recorder.output
    assert 'Failed to publish log message to rosout' not in recorder.output
    assert 'Traceback' not in recorder.output
