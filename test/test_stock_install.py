"""The stock ROS 2 Jazzy recipe (docs/stock_install.md): rosdep keys, declared dependencies, pins.

What can be checked here without /opt/ros and without rosdep's network sources:

* every dependency of every ``package.xml`` is a key rosdep knows or a package of this
  workspace: the keys hrc uses are listed below, each found in ros/rosdistro (its source);
* every third-party module a package imports (at module level or lazily) is declared in that
  package's ``package.xml`` by its rosdep key, or has no rosdep key and is pinned in
  ``requirements-stock.txt``, the recipe's pip step;
* ``requirements-stock.txt`` installs no ROS wheel and no numpy (the system's numpy stays: the
  ROS debs' C extensions are built against it), names the CPU torch build, pins what
  ``requirements.txt`` pins, and every pin accepts Ubuntu 24.04's numpy (its metadata, read
  from the same versions installed here);
* the recipe's venv step: a venv made with ``--system-site-packages`` over a Python that has
  the ROS packages (here the pip ROS wheels stand in for /opt/ros/jazzy) imports rclpy and
  the system's numpy, not one of its own.
"""

import ast
import importlib.metadata
import os
import pathlib
import re
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

from packaging.requirements import Requirement
from packaging.version import Version

ROOT = pathlib.Path(__file__).resolve().parents[1]
# The rosdep keys hrc's package.xml files use, each checked by hand in ros/rosdistro at
# 8468e88ccd523427f9131e39d2af0938f1c298b2 (2026-08-22): rosdep/base.yaml and
# rosdep/python.yaml (system and pip keys), jazzy/distribution.yaml (ROS packages).
ROS_PACKAGE_KEYS = {
    'ament_cmake', 'ament_index_python', 'builtin_interfaces', 'diagnostic_msgs',
    'geometry_msgs', 'rcl_interfaces', 'rclpy', 'rosgraph_msgs', 'rosidl_default_generators',
    'rosidl_default_runtime', 'sensor_msgs', 'std_msgs', 'std_srvs', 'visualization_msgs'}
SYSTEM_KEYS = {     # rosdep/python.yaml: apt packages on Ubuntu
    'python3-matplotlib', 'python3-numpy', 'python3-pil', 'python3-pytest', 'python3-scipy',
    'python3-torch', 'python3-yaml'}
PIP_KEYS = {        # rosdep/python.yaml: pip packages (there is no apt package of these)
    'mcap-ros2-support', 'python3-gymnasium-pip', 'python3-pybullet-pip',
    'python3-rosbags-pip', 'python3-stable-baselines3-pip'}
KNOWN_KEYS = ROS_PACKAGE_KEYS | SYSTEM_KEYS | PIP_KEYS
# The rosdep key of each third-party module an hrc package imports.
MODULE_KEYS = {
    'numpy': 'python3-numpy', 'yaml': 'python3-yaml', 'matplotlib': 'python3-matplotlib',
    'scipy': 'python3-scipy', 'torch': 'python3-torch', 'PIL': 'python3-pil',
    'pybullet': 'python3-pybullet-pip', 'rosbags': 'python3-rosbags-pip',
    'mcap_ros2': 'mcap-ros2-support', 'gymnasium': 'python3-gymnasium-pip',
    'stable_baselines3': 'python3-stable-baselines3-pip'}
# Modules without a rosdep key there: the recipe's pip step installs them (their pin names).
# (foxglove-sdk, added later, was not looked up in rosdistro: pinned for pip either way.)
PIP_ONLY = {'mcap': 'mcap', 'zstandard': 'zstandard', 'ray': 'ray', 'pettingzoo': 'pettingzoo',
            'foxglove': 'foxglove-sdk'}
UBUNTU_NOBLE_NUMPY = '1.26.4'   # python3-numpy of Ubuntu 24.04, what /opt/ros/jazzy's debs use


def packages() -> dict:
    """Return {package name: its folder} of the workspace."""
    return {path.parent.name: path.parent for path in sorted(ROOT.glob('src/*/package.xml'))}


def declared(folder: pathlib.Path) -> set:
    """Return the dependencies a package.xml declares (every kind)."""
    tree = ElementTree.parse(folder / 'package.xml')
    return {element.text.strip() for element in tree.getroot()
            if element.tag.endswith('depend') and element.text}


def imported_modules(folder: pathlib.Path) -> set:
    """Return the top-level modules the package's own modules import (tests left out)."""
    found = set()
    for path in (folder / folder.name).rglob('*.py'):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                found |= {alias.name.split('.')[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                found.add(node.module.split('.')[0])
    return found


def pins(path: pathlib.Path) -> dict:
    """Return {normalized name: version} of a requirements file's ``name==version`` lines."""
    result = {}
    for line in path.read_text().splitlines():
        line = line.split('#')[0].strip()
        if '==' in line and not line.startswith('-'):
            name, version = line.split('==')
            result[re.sub(r'[-_.]+', '-', name.split('[')[0]).lower()] = version.strip()
    return result


def test_every_package_xml_dependency_is_a_key_rosdep_knows():
    workspace = set(packages())
    unknown = {name: sorted(declared(folder) - KNOWN_KEYS - workspace)
               for name, folder in packages().items()}
    assert not any(unknown.values()), {name: keys for name, keys in unknown.items() if keys}


def test_every_imported_library_is_declared_or_pinned_for_pip():
    stock = pins(ROOT / 'requirements-stock.txt')
    standard = set(sys.stdlib_module_names)
    workspace = set(packages())
    problems = []
    for name, folder in packages().items():
        keys = declared(folder)
        for module in sorted(imported_modules(folder) - standard - workspace):
            if module in ROS_PACKAGE_KEYS or module == 'hrc_testing':
                if module not in keys and module != 'hrc_testing':
                    problems.append(f'{name}: imports {module}, not in its package.xml')
            elif module in MODULE_KEYS:
                if MODULE_KEYS[module] not in keys:
                    problems.append(f'{name}: imports {module}, its key {MODULE_KEYS[module]} '
                                    f'is not in its package.xml')
            elif module in PIP_ONLY:
                if PIP_ONLY[module] not in stock:
                    problems.append(f'{name}: imports {module} (no rosdep key), not pinned in '
                                    f'requirements-stock.txt')
            else:
                problems.append(f'{name}: imports {module}: no rosdep key known to this test')
    assert not problems, problems


def test_the_stock_pins_keep_the_systems_numpy_and_take_the_cpu_torch():
    text = (ROOT / 'requirements-stock.txt').read_text()
    stock, full = pins(ROOT / 'requirements-stock.txt'), pins(ROOT / 'requirements.txt')
    assert 'numpy' not in stock and not any(name.startswith('ros-') for name in stock)
    assert re.search(r'^--extra-index-url https://download\.pytorch\.org/whl/cpu$', text, re.M)
    assert stock['torch'].endswith('+cpu'), stock['torch']
    for name, version in stock.items():     # the same versions as the venv of `make setup`
        if name in full:
            assert Version(version).public == Version(full[name]).public, (name, version)
    for name in set(full) - set(stock):     # what is left out: the ROS wheels, colcon, numpy
        assert name.startswith(('ros-', 'colcon-')) or name in ('numpy', 'pyyaml', 'py-spy',
                                                               'ruff'), name
    refused = []
    for name in stock:
        try:
            requirements = importlib.metadata.distribution(name).requires or []
        except importlib.metadata.PackageNotFoundError:
            continue
        for requirement in map(Requirement, requirements):
            if (requirement.name.lower() == 'numpy' and not requirement.marker
                    and not requirement.specifier.contains(UBUNTU_NOBLE_NUMPY)):
                refused.append(f'{name}: numpy{requirement.specifier}')
    assert not refused, refused


def test_a_venv_over_the_ros_python_uses_its_rclpy_and_numpy(tmp_path):
    """The recipe's venv: --system-site-packages sees the ROS packages and their numpy."""
    # The stand-in for /opt/ros/jazzy: this Python's site-packages (the pip ROS wheels), put
    # on the path as `source /opt/ros/jazzy/setup.bash` puts the debs' on PYTHONPATH.
    ros_site = next(path for path in map(pathlib.Path, sys.path)
                    if (path / 'rclpy').is_dir())
    venv = tmp_path / 'venv'
    subprocess.run([sys.executable, '-m', 'venv', '--system-site-packages', '--without-pip',
                    str(venv)], check=True, timeout=120)
    probe = ('import numpy, rclpy, sys; print(numpy.__file__); print(rclpy.__file__); '
             'print(sys.prefix)')
    env = {name: value for name, value in os.environ.items()
           if name not in ('VIRTUAL_ENV', 'PYTHONHOME')}     # the ROS libraries' path stays
    env['PYTHONPATH'] = str(ros_site)
    result = subprocess.run([str(venv / 'bin' / 'python'), '-c', probe], capture_output=True,
                            text=True, timeout=120, env=env)
    assert result.returncode == 0, result.stderr
    numpy_file, rclpy_file, prefix = result.stdout.split()
    assert pathlib.Path(prefix) == venv
    assert pathlib.Path(rclpy_file).is_relative_to(ros_site)
    assert not pathlib.Path(numpy_file).is_relative_to(venv)   # not a numpy of its own
