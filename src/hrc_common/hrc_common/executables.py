"""Find node executables as ``ros2 run`` does (pure: the ament index, no rclpy).

A package is found through the ament index: the first prefix in ``AMENT_PREFIX_PATH`` holding
``share/ament_index/resource_index/packages/<package>``; its executables are the executable
files in ``<prefix>/lib/<package>/``. The session runner, the experiment runner, the tests and
the ``ros2`` shim (``scripts/bin/ros2``) all use this one lookup.
"""

import os
import pathlib


class ExecutableNotFound(LookupError):
    """The package or the executable is not installed; the message says which, as ros2 does."""


def package_prefix(package: str) -> pathlib.Path:
    """Return the install prefix of ``package`` (ament index); ExecutableNotFound if none."""
    for prefix in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep):
        if prefix and os.path.isfile(os.path.join(
                prefix, 'share', 'ament_index', 'resource_index', 'packages', package)):
            return pathlib.Path(prefix)
    raise ExecutableNotFound(f"Package '{package}' not found")


def executable_path(package: str, executable: str) -> pathlib.Path:
    """Return ``<prefix>/lib/<package>/<executable>`` (whether or not it exists yet)."""
    return package_prefix(package) / 'lib' / package / executable


def package_executables(package: str) -> list:
    """Return the names of the executable files in ``<prefix>/lib/<package>/``, sorted."""
    directory = package_prefix(package) / 'lib' / package
    if not directory.is_dir():
        return []
    return sorted(path.name for path in directory.iterdir()
                  if path.is_file() and os.access(path, os.X_OK))


def find_executable(package: str, executable: str) -> pathlib.Path:
    """Return the executable ``ros2 run <package> <executable>`` would start.

    Raises ExecutableNotFound naming the package's executables when it has no such one.
    """
    path = executable_path(package, executable)
    if path.is_file() and os.access(path, os.X_OK):
        return path
    known = package_executables(package)
    raise ExecutableNotFound(
        f"No executable found: package '{package}' has no executable '{executable}' "
        f"(it has: {', '.join(known) if known else 'none'})")
