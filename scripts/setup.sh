#!/usr/bin/env bash
# Set up everything from a fresh clone: .venv, pinned requirements, the ROS wheel fix, colcon
# build. Idempotent: each stage is skipped when its inputs have not changed since it last ran.
set -euo pipefail
cd "$(dirname "$0")/.."
top=$PWD
venv=$top/.venv
python=${PYTHON:-python3}

stamp_of() { cat "$@" | sha256sum | cut -c1-16; }

# 1. the virtual environment, with the machine's python3
if [ ! -x "$venv/bin/python" ]; then
  echo "setup: creating $venv with $($python --version 2>&1)"
  "$python" -m venv "$venv"
fi

# 2. pinned requirements (re-run only when requirements.txt or constraints.txt change)
req_stamp=$venv/.requirements-$(stamp_of requirements.txt constraints.txt)
if [ ! -f "$req_stamp" ]; then
  echo "setup: installing requirements.txt (pinned; constraints.txt pins the rest)"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check \
    -r requirements.txt -c constraints.txt
  rm -f "$venv"/.requirements-*
  touch "$req_stamp"
fi

# 2b. the browser the display tests drive (Debian's chromium and its WebDriver). Installed with
# apt-get when missing and we are root; otherwise say how, and the browser tests fail with that.
if ! command -v chromium >/dev/null 2>&1 || ! command -v chromedriver >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "setup: installing Debian's chromium and chromium-driver (browser tests of the display)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null
    apt-get install -y -qq chromium chromium-driver >/dev/null
  else
    echo "setup: chromium/chromedriver missing; as root: apt-get install chromium chromium-driver"
  fi
fi

# 3. the ROS wheels' exported CMake targets point at the wheel build machine: fix once
fix_stamp=$venv/.ros-wheels-fixed-$(stamp_of requirements.txt scripts/fix_ros_wheels.py)
if [ ! -f "$fix_stamp" ]; then
  "$venv/bin/python" scripts/fix_ros_wheels.py
  rm -f "$venv"/.ros-wheels-fixed-*
  touch "$fix_stamp"
fi

# 4. colcon build, only when a package file changed since the last successful build. One build
# at a time per checkout: concurrent `make` calls wait for the lock instead of racing in build/.
mkdir -p "$top/log"
exec 9>"$top/log/.setup.lock"
flock 9
build_stamp=$top/install/.hrc-build-stamp
newest=$(find src colcon.meta -newer "$build_stamp" -not -name '*.pyc' -print -quit 2>/dev/null || true)
if [ ! -f "$build_stamp" ] || [ -n "$newest" ]; then
  echo "setup: colcon build${newest:+ ($newest changed)}"
  # shellcheck disable=SC1091
  source "$venv/bin/activate"
  # rosidl finds its type supports through the ament index of the venv prefix
  export CMAKE_PREFIX_PATH=$venv AMENT_PREFIX_PATH=$venv
  start=$(date +%s)
  mkdir -p log
  colcon --log-base log build --symlink-install --metas colcon.meta \
    --event-handlers console_cohesion+ summary+ status- > log/colcon-build.txt 2>&1 \
    || { mkdir -p log; cat log/colcon-build.txt; echo "setup: colcon build failed"; exit 1; }
  echo "setup: colcon build done in $(( $(date +%s) - start )) s"
  touch "$build_stamp"
fi
