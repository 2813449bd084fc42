#!/usr/bin/env python3
"""Make the ROS 2 Jazzy PyPI wheels usable for building interface packages with colcon.

The wheels' exported CMake targets (share/<pkg>/cmake/*Export.cmake) carry include
directories of the machine the wheels were built on (/opt/python/cpXY-cpXY/...). CMake
refuses an imported target whose include directory does not exist, so every rosidl build
against those targets fails. This script rewrites those two paths to this venv's own:

* the CPython headers   -> sysconfig.get_paths()['include']
* the numpy headers     -> numpy.get_include()

It is idempotent: a second run finds nothing to rewrite and says so. Run it with the venv's
Python; it edits files under sys.prefix only.
"""

import pathlib
import re
import sys
import sysconfig

import numpy

# Prefix of the manylinux build image the wheels came from, e.g. /opt/python/cp311-cp311.
BUILD_PREFIX = r'/opt/python/cp\d+-cp\d+'
PYTHON_INCLUDE = re.compile(BUILD_PREFIX + r'/include/python3\.\d+')
NUMPY_INCLUDE = re.compile(
    BUILD_PREFIX + r'/lib/python3\.\d+/site-packages/numpy/(?:_core|core)/include')


def rewrite(text: str) -> str:
    """Return text with the build machine's include directories replaced by ours."""
    text = NUMPY_INCLUDE.sub(numpy.get_include(), text)
    return PYTHON_INCLUDE.sub(sysconfig.get_paths()['include'], text)


def main() -> int:
    """Rewrite every exported CMake file of the venv that needs it."""
    share = pathlib.Path(sys.prefix) / 'share'
    if not share.is_dir():
        print(f'fix_ros_wheels: {share} does not exist: is this the venv with the ROS wheels?')
        return 1
    changed = 0
    for cmake_file in share.glob('*/cmake/*.cmake'):
        text = cmake_file.read_text()
        new_text = rewrite(text)
        if new_text != text:
            cmake_file.write_text(new_text)
            changed += 1
    print(f'fix_ros_wheels: rewrote include directories in {changed} CMake files under {share}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
