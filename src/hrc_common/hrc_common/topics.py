"""Default topic and service names of the hrc graph (all remappable with --ros-args -r)."""

STATE = '/hrc/state'
ROBOT_CMD_WRENCH = '/hrc/robot/cmd_wrench'
HUMAN_CMD_WRENCH = '/hrc/human/cmd_wrench'
HUMAN_ACTION = '/hrc/human/action'
SESSION = '/hrc/session'
EPISODE = '/hrc/episode'
AGENT_STEP = '/hrc/agent/step'
CLOCK = '/clock'
JOY = '/joy'
CAMERA_IMAGE = '/hrc/sim/image'
MARKERS = '/hrc/sim/markers'
RESET_SERVICE = '/hrc/sim/reset'
