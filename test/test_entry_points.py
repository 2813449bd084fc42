"""Do what `ros2 run <pkg> <exe>` does, for every console script of every package.

`ros2 run` looks the package up in the ament index, then runs `<prefix>/lib/<pkg>/<exe>`. This
test finds every console script declared by every ament_python package under src/, resolves it
the same way, checks it is an executable file, and runs it with --help (no ROS graph needed).
"""

import configparser
import importlib.metadata
import os
import pathlib
import subprocess

from ament_index_python.packages import get_package_prefix
import pytest

SOURCE = pathlib.Path(__file__).resolve().parents[1] / 'src'
PYTHON_PACKAGES = sorted(path.parent.name for path in SOURCE.glob('*/setup.py'))


def console_scripts():
    """Yield (package, executable) for every console script of every package under src/."""
    for package in PYTHON_PACKAGES:
        for entry_point in importlib.metadata.distribution(package).entry_points:
            if entry_point.group == 'console_scripts':
                yield package, entry_point.name


SCRIPTS = list(console_scripts())
# The executables the README promises: the nodes (`ros2 run <package> <node>`) and the one
# command line `hrc` (every other command is a verb of it, no alias is left).
PROMISED = {('hrc_sim_node', 'sim_node'), ('hrc_agent_node', 'agent_node'),
            ('hrc_joystick_node', 'human_node'), ('hrc_bag', 'recorder_node'),
            ('hrc_bag', 'replay_node'), ('hrc_live', 'display_node'),
            ('hrc_live', 'foxglove_node'), ('hrc_bringup', 'hrc')}


def test_the_console_scripts_are_the_nodes_and_hrc():
    assert set(SCRIPTS) == PROMISED, set(SCRIPTS) ^ PROMISED


def test_every_python_package_installs_its_scripts_where_ros2_run_looks():
    for package in PYTHON_PACKAGES:
        setup_cfg = configparser.ConfigParser()
        setup_cfg.read(SOURCE / package / 'setup.cfg')
        assert setup_cfg['install']['install_scripts'] == f'$base/lib/{package}', package
        assert setup_cfg['develop']['script_dir'] == f'$base/lib/{package}', package
        prefix = pathlib.Path(get_package_prefix(package))
        assert (prefix / 'share' / package / 'package.xml').is_file(), package
        marker = prefix / 'share' / 'ament_index' / 'resource_index' / 'packages' / package
        assert marker.is_file(), package


@pytest.mark.slow
@pytest.mark.parametrize('package, executable', SCRIPTS,
                         ids=[f'{p}/{e}' for p, e in SCRIPTS])
def test_ros2_run_finds_and_runs(package, executable):
    path = pathlib.Path(get_package_prefix(package)) / 'lib' / package / executable
    assert path.is_file(), f'{path} missing: ros2 run {package} {executable} would fail'
    assert os.access(path, os.X_OK), f'{path} is not executable'
    result = subprocess.run([str(path), '--help'], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert 'usage' in result.stdout.lower(), result.stdout
