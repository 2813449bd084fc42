"""The command line of ``hrc session --engine inprocess``: its parser, light to import.

``hrc session --engine inprocess --help`` is answered from here without loading torch or
PyBullet (the engine loads them); ``hrc_engine.inprocess_session.parse_args`` checks the values.
"""

import argparse

from hrc_common.session_plan import add_adapt_option, add_learning_option


def build_parser() -> argparse.ArgumentParser:
    """Return the parser of ``hrc session --engine inprocess`` (its flags and help)."""
    parser = argparse.ArgumentParser(
        prog='hrc session --engine inprocess', description='Run one hrc session (one case, '
        'one seed) in one process: physics, step protocol, PPO agent, simulated human, '
        'evaluation, checkpoints and the bags of the graph, without ROS communication.')
    parser.add_argument('--case', type=int, default=2, help="case 1..8: the paper's six, 7-8 "
                        'partners first (from their pre-trained checkpoint; default 2)')
    parser.add_argument('--seed', type=int, default=0, help='session seed (default 0)')
    parser.add_argument('--episodes', type=int, default=0,
                        help='max training episodes (default: the learning configuration)')
    parser.add_argument('--eval-episodes', type=int, default=-1,
                        help='evaluation episodes (default: params/agent.yaml)')
    parser.add_argument('--session-id', default='', help='default: case<N>-seed<S>-<time>')
    parser.add_argument('--bags-dir', default='bags', help='bags land in <bags-dir>/<id>/')
    parser.add_argument('--runs-dir', default='runs',
                        help='session.yaml and checkpoints in <runs-dir>/ (default runs)')
    parser.add_argument('--no-record', action='store_true', help='write no bags')
    parser.add_argument('--no-checkpoints', action='store_true', help='write no checkpoints')
    parser.add_argument('--profile', dest='human_profile', default='',
                        help='simulated-human profile (params/sim_human.yaml)')
    add_learning_option(parser)
    # The flags of the graph's session: the values without wall time are accepted, so one
    # command line works with either engine; any other value is refused with the reason.
    parser.add_argument('--human', dest='human_input', default='sim',
                        help='sim (default: the simulated human), model (a cloned model, '
                        '--set human.model_file=PATH) or script (a scripted stick, --set '
                        'human.script_file=PATH); a person at a device or /joy needs --engine '
                        'graph')
    parser.add_argument('--mode', default='lockstep', help='lockstep only (realtime needs '
                        '--engine graph)')
    parser.add_argument('--params-dir', default='', help='parameter files (default: ./params '
                        'in a checkout, else the installed ones)')
    parser.add_argument('--resume-from', default='', help='continue from this checkpoint')
    parser.add_argument('--start-from', default='', metavar='CHECKPOINT',
                        help="a new session from a finished session's policy (a returning "
                        "person): the strategy's last step, its first episode judges it "
                        '(--adapt-from for a new person: it learns from the first)')
    add_adapt_option(parser)
    parser.add_argument('--set', action='append', default=[], metavar='NODE.NAME=VALUE',
                        help='override a node parameter (YAML value), as with session')
    parser.add_argument('--json', action='store_true', help='print the result as JSON')
    return parser
