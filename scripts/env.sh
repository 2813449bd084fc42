# Source this file to use the workspace: the venv (ROS 2 Jazzy prefix) and the colcon install.
# shellcheck shell=bash
_hrc_top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck disable=SC1091
source "$_hrc_top/.venv/bin/activate"
# The venv is the ROS prefix of the wheels (share/, lib/); the install's setup prepends ours.
export AMENT_PREFIX_PATH=$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}
# shellcheck disable=SC1091
source "$_hrc_top/install/setup.bash"
export ROS_AUTOMATIC_DISCOVERY_RANGE=${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}
unset _hrc_top
