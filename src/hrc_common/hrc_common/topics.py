"""Default topic and service names of the hrc graph (all remappable with --ros-args -r).

``TYPES`` gives the message type of each hrc topic (type names of ``hrc_common.contract``).
"""

from hrc_common.contract import (AGENT_STEP_TYPE, EPISODE_SUMMARY_TYPE, HUMAN_ACTION_TYPE,
                                 JOINT_STATE_TYPE, SESSION_STATUS_TYPE, STRING_TYPE,
                                 TASK_STATE_TYPE, WRENCH_STAMPED_TYPE)

STATE = '/hrc/state'
# States within a control period at the human's rate (TaskState, slice > 0), for the human node
# and the person's page; not recorded (the period's state carries the applied human commands).
SLICE_STATE = '/hrc/sim/slice_state'
ROBOT_CMD_WRENCH = '/hrc/robot/cmd_wrench'
HUMAN_CMD_WRENCH = '/hrc/human/cmd_wrench'
HUMAN_ACTION = '/hrc/human/action'
SESSION = '/hrc/session'
EPISODE = '/hrc/episode'
AGENT_STEP = '/hrc/agent/step'
# The system as ROS tools expect it (RViz, Foxglove, robot_state_publisher): the sim's URDF
# (std_msgs/String, transient local) and its three joints at the state's rate, stamped as the
# state (sensor_msgs/JointState: slide m, hinge rad, roll m; hrc_sim_node.body_geometry).
ROBOT_DESCRIPTION = '/robot_description'
JOINT_STATES = '/joint_states'
CLOCK = '/clock'
JOY = '/joy'
CAMERA_IMAGE = '/hrc/sim/image'
MARKERS = '/hrc/sim/markers'
RESET_SERVICE = '/hrc/sim/reset'
# The human node's input status (diagnostic_msgs/DiagnosticStatus, transient local).
HUMAN_INPUT = '/hrc/human/input'
# The session runner's "joystick disconnected" words for the pages (std_msgs/String).
INPUT_LOST = '/hrc/session/input_lost'
# Why the session runner waits ('' = it does not): for the person's input before it starts the
# nodes (and what to do), or for the agent it starts again after a resume (std_msgs/String,
# transient local): the console and ``hrc operator status`` say it, the page "please wait".
RUNNER_WAITING = '/hrc/session/runner_waiting'
# How far the recorder has taken the session's states (std_msgs/Header: stamp = the newest
# /hrc/state it holds, frame_id = its session id), after each batch; a lockstep sim that
# awaits its recorder publishes no state far ahead of it (hrc_sim_node.recorder_gate).
RECORDER_PROGRESS = '/hrc/recorder/progress'
# What a replay node replays ('' = nothing: live), std_msgs/String, transient local: the pages
# mark a replay as one.
REPLAY = '/hrc/replay'

# The type of each topic of the session graph (by default name): what a recording holds.
TYPES = {
    STATE: TASK_STATE_TYPE,
    ROBOT_CMD_WRENCH: WRENCH_STAMPED_TYPE,
    HUMAN_CMD_WRENCH: WRENCH_STAMPED_TYPE,
    HUMAN_ACTION: HUMAN_ACTION_TYPE,
    SESSION: SESSION_STATUS_TYPE,
    EPISODE: EPISODE_SUMMARY_TYPE,
    AGENT_STEP: AGENT_STEP_TYPE,
    ROBOT_DESCRIPTION: STRING_TYPE,
    JOINT_STATES: JOINT_STATE_TYPE,
}
