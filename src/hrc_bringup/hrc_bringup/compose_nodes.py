"""Several nodes of a session in one process, on one executor (a component container).

    python -m hrc_bringup.compose_nodes sim human --ros-args --params-file <session params>
    HRC_COMPOSE=sim,human hrc session --case 5        # the session runner starts them so

Each node stays its own rclpy ``Node`` (its name, parameters, topics and services: the graph
looks the same to every other node and tool); they share one process, one DDS participant and
one executor (``HRC_EXECUTOR``, ``lean`` by default), which serves them in the order named. In
a lockstep session the sim and the human node exchange a state and a command every slice (ten
a control step at the human's own rate): composed, an exchange wakes no other process. Each
node reads its own section of the parameter file (the session runner's file has one per node);
a ``-p name:=value`` applies to every composed node.

``hrc session`` starts one process per node by default (what ``ros2 run`` users expect);
``HRC_COMPOSE`` names the nodes it starts as one process instead (two or more of sim, human,
recorder; the agent stays alone: the session restarts it on a resume and reads its exit code).

Exit codes: 0 after Ctrl-C/SIGTERM, 2 for bad parameters or node names (every reason at once),
3 when a composed recorder cannot write its bags (or a composed sim waited too long for it).
"""

import importlib
import os
import sys

from hrc_bag.format import RecordingError
from hrc_common.nodes import report_bad_parameters, run_nodes, wants_help
from hrc_sim_node.recorder_wait import RecorderStalled

EXECUTABLE = 'compose_nodes'
# node name -> (module, class) of the node
NODE_CLASSES = {
    'sim': ('hrc_sim_node.sim_node', 'SimNode'),
    'human': ('hrc_joystick_node.human_node', 'HumanNode'),
    'recorder': ('hrc_bag.recorder_node', 'RecorderNode'),
    'agent': ('hrc_agent_node.agent_node', 'AgentNode'),
}
# HRC_COMPOSE: the nodes `hrc session` starts as one process (comma separated)
COMPOSE_VARIABLE = 'HRC_COMPOSE'
SESSION_COMPOSABLE = ('sim', 'human', 'recorder')
EXIT_RECORDING_FAILED = 3
SUMMARY = (f'Run several hrc nodes ({", ".join(NODE_CLASSES)}) in one process on one executor, '
           f'each its own node with its own section of the --params-file. Example: '
           f'python -m hrc_bringup.compose_nodes sim human --ros-args --params-file '
           f'parameters.yaml')


def names_problems(names, allowed=tuple(NODE_CLASSES)) -> list:
    """Return why ``names`` cannot be composed (empty if they can)."""
    problems = [f'{name!r} is not a node that can be composed ({", ".join(allowed)})'
                for name in names if name not in allowed]
    if len(set(names)) != len(names):
        problems.append(f'a node is named twice in {", ".join(names)}')
    if len(names) < 2:
        problems.append(f'name two or more nodes to compose ({", ".join(allowed)})')
    return problems


def session_composition(environ=None) -> tuple:
    """Return (the nodes ``HRC_COMPOSE`` names, the reasons it cannot be used).

    Unset or empty: ([], []), every node its own process.
    """
    value = (os.environ if environ is None else environ).get(COMPOSE_VARIABLE, '').strip()
    if not value:
        return [], []
    names = [name.strip() for name in value.split(',') if name.strip()]
    problems = names_problems(names, SESSION_COMPOSABLE)
    return names, [f'{COMPOSE_VARIABLE}={value!r}: {problem}' for problem in problems]


def node_factory(name: str):
    """Return a callable that imports and makes the node ``name``."""
    module, cls = NODE_CLASSES[name]

    def make():
        return getattr(importlib.import_module(module), cls)()
    return make


def main(argv=None) -> int:
    """Run the named nodes in this process (see the module docstring)."""
    argv = list(sys.argv if argv is None else argv)
    user_args = argv[1:argv.index('--ros-args')] if '--ros-args' in argv else argv[1:]
    names = [arg for arg in user_args if not arg.startswith('-')]
    if not wants_help(argv):
        problems = names_problems(names)
        if problems:
            return report_bad_parameters(EXECUTABLE, problems)
    try:
        return run_nodes([node_factory(name) for name in names], EXECUTABLE, SUMMARY, None,
                         argv)
    except (RecordingError, RecorderStalled) as error:
        print(f'[ERROR] [{EXECUTABLE}] recording stopped, the session must stop: {error}',
              file=sys.stderr, flush=True)
        return EXIT_RECORDING_FAILED


if __name__ == '__main__':
    sys.exit(main())
