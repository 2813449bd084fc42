"""The nodes' parameter files ``params/<node>.yaml``, generated from the nodes' dataclasses.

Each node's parameters are declared once, in its dataclass; this table names the dataclass of
each file (it lives here, in the top layer, because it imports every node package) and
:mod:`hrc_common.params_yaml` renders them::

    python -m hrc_bringup.params_files --write    # regenerate params/<node>.yaml
    python -m hrc_bringup.params_files --check    # exit 1 and name the files that drifted

``src/hrc_bringup/test/test_params_files.py`` runs the check, so a changed dataclass with a
stale file fails the suite. The data files of ``params/`` (cases, task tree, simulated-human
profiles, learning configurations) are not parameter files and are written by hand.
"""

import argparse
import pathlib
import sys

from hrc_agent_node.config import AgentParams
from hrc_bag.recorder_params import RecorderParams
from hrc_bag.replay import ReplayParams
from hrc_common import params_yaml
from hrc_common.paths import params_dir
from hrc_common.session_plan import NODES
from hrc_joystick_node.human_core import HumanParams
from hrc_live.display_params import DisplayParams
from hrc_live.foxglove_view import FoxgloveParams
from hrc_sim_node.sim_params import SimParams

COMMAND = 'python -m hrc_bringup.params_files --write'

# file name in params/ -> (node name: the file's section, the node's parameter dataclass)
PARAMETER_FILES = {
    'sim.yaml': ('sim', SimParams),
    'agent.yaml': ('agent', AgentParams),
    'human.yaml': ('human', HumanParams),
    'recorder.yaml': ('recorder', RecorderParams),
    'replay.yaml': ('replay', ReplayParams),
    'display.yaml': ('display', DisplayParams),
    'foxglove.yaml': ('foxglove', FoxgloveParams),
}


def notice(file_name: str) -> str:
    """Return the header paragraph of a file: how it is made and how to change a value."""
    node_name, params_cls = PARAMETER_FILES[file_name]
    session = (f', `--set {node_name}.NAME=VALUE` on `hrc session`' if node_name in NODES
               else '')
    return (f'Generated from {params_cls.__module__}.{params_cls.__qualname__} by `{COMMAND}`: '
            "do not edit here; change the dataclass (a field's description is its comment) and "
            'regenerate; a test fails when the two differ. For one run: `--ros-args -p '
            f"NAME:=VALUE` or `--params-file FILE` on the node's command line{session}.")


def rendered() -> dict:
    """Return {file name: text} of every parameter file, rendered from its dataclass."""
    return {name: params_yaml.render(params_cls, node_name, notice(name))
            for name, (node_name, params_cls) in PARAMETER_FILES.items()}


def main(argv=None) -> int:
    """Write or check the parameter files; exit 1 when --check finds drift."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    action = parser.add_mutually_exclusive_group(required=True)
    action.add_argument('--write', action='store_true', help='regenerate the files')
    action.add_argument('--check', action='store_true',
                        help='exit 1 if a file differs from its dataclass')
    parser.add_argument('--params-dir', type=pathlib.Path, default=None,
                        help="folder of the files (default: this checkout's params/)")
    options = parser.parse_args(argv)
    folder = options.params_dir or pathlib.Path(params_dir())
    if options.write:
        changed = params_yaml.write(rendered(), folder)
        print(f'wrote {", ".join(changed)}' if changed else 'every file was up to date')
        return 0
    stale = params_yaml.drift(rendered(), folder)
    for name in stale:
        print(f'{folder / name}: differs from its dataclass; run {COMMAND}', file=sys.stderr)
    return 1 if stale else 0


if __name__ == '__main__':
    sys.exit(main())
