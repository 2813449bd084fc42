# Source this file to use the workspace: the venv (ROS 2 Jazzy prefix) and the colcon install.
# Works from any directory: `source /path/to/hrc/scripts/env.sh` (bash).
# shellcheck shell=bash
# bash only (it finds itself through BASH_SOURCE; the colcon install's setup.bash): any other
# shell (sh, dash, zsh) is told so instead of failing half-way.
if [ -z "${BASH_VERSION:-}" ]; then
  echo "scripts/env.sh needs bash (this shell is not bash): run 'bash', then 'source scripts/env.sh'" >&2
  return 1 2>/dev/null || exit 1
fi
_hrc_top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck disable=SC1091
source "$_hrc_top/.venv/bin/activate"
# The venv is the ROS prefix of the wheels (share/, lib/); the install's setup prepends ours.
export AMENT_PREFIX_PATH=$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}
# shellcheck disable=SC1091
source "$_hrc_top/install/setup.bash"
# The `hrc` command (hrc_bringup/cli.py): its install folder holds only that executable, so
# putting it on PATH adds nothing else. `ros2 run hrc_bringup hrc` runs the same.
case ":$PATH:" in
  *":$_hrc_top/install/hrc_bringup/lib/hrc_bringup:"*) ;;
  *) export PATH="$_hrc_top/install/hrc_bringup/lib/hrc_bringup:$PATH" ;;
esac
export ROS_AUTOMATIC_DISCOVERY_RANGE=${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}
# LOCALHOST limits discovery to this host, but Fast DDS would still bind its receive ports to
# 0.0.0.0: the loopback profile binds them to 127.0.0.1 (params/fastdds/loopback.xml says what
# remains). Only when no other profile is chosen; two hosts: docs/two_hosts.md.
if [ "$ROS_AUTOMATIC_DISCOVERY_RANGE" = LOCALHOST ] && [ -z "${FASTRTPS_DEFAULT_PROFILES_FILE:-}" ] \
    && [ -z "${FASTDDS_DEFAULT_PROFILES_FILE:-}" ]; then
  export FASTRTPS_DEFAULT_PROFILES_FILE=$_hrc_top/params/fastdds/loopback.xml
fi
# The pip wheels do not ship the ROS 2 CLI: without a real `ros2`, put hrc's shim on PATH
# (scripts/bin/ros2: `ros2 run` with the same ament-index lookup; it says it is the shim).
# Its notice comes once per shell, here, not on every call (HRC_ROS2_SHIM_NOTICE tells the shim).
if ! command -v ros2 >/dev/null 2>&1 || [ "$(command -v ros2)" = "$_hrc_top/scripts/bin/ros2" ]; then
  case ":$PATH:" in
    *":$_hrc_top/scripts/bin:"*) ;;
    *) export PATH="$_hrc_top/scripts/bin:$PATH" ;;
  esac
  if [ -z "${HRC_ROS2_SHIM_NOTICE:-}" ]; then
    python3 "$_hrc_top/scripts/bin/ros2" --notice
    export HRC_ROS2_SHIM_NOTICE=shown
  fi
fi
unset _hrc_top
