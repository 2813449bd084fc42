"""The command line of ``hrc experiment``: its parser, light to import.

``hrc experiment --help`` is answered from here without loading torch, PyBullet or ray (the
sweep's modules load them); ``hrc_bringup.experiment.parse_args`` checks the values.
"""

import argparse

from hrc_common.cases import paper_case_ids
from hrc_common.session_plan import add_learning_option

ENGINES = ('inprocess', 'graph')


def build_parser() -> argparse.ArgumentParser:
    """Return the parser of ``hrc experiment`` (its flags and help)."""
    parser = argparse.ArgumentParser(
        prog='hrc experiment', description='Run paper cases x seeds (x simulated-human profiles) '
        'headless, each session a task on a local process pool or a Ray cluster, then write '
        'the study of all sessions (hrc_study).')
    parser.add_argument('--cases', type=int, nargs='+', default=list(paper_case_ids()),
                        help="cases to run (default: the paper's of params/cases.yaml, "
                        f"{' '.join(map(str, paper_case_ids()))})")
    parser.add_argument('--seeds', type=int, default=10,
                        help='seeds per case, each a different simulated person (default 10)')
    parser.add_argument('--first-seed', type=int, default=0, help='first seed (default 0)')
    parser.add_argument('--profiles', nargs='+', default=[''], metavar='PROFILE[:SEEDS]',
                        help='simulated-human profiles (params/sim_human.yaml), each with '
                        'its own number of seeds if given (default --seeds); each runs '
                        "every case and seed (default: the human node's profile)")
    parser.add_argument('--same-person', action='store_true',
                        help='every seed with the profile itself (default: seed N is person '
                        'N of the population around the profile)')
    parser.add_argument('--engine', choices=ENGINES, default='inprocess',
                        help='inprocess (default): one process per session; graph: the ROS '
                        'nodes over DDS per session')
    add_learning_option(parser)
    parser.add_argument('--episodes', type=int, default=0,
                        help='max training episodes per session (default: the learning '
                        'configuration)')
    parser.add_argument('--eval-episodes', type=int, default=-1,
                        help='final evaluation episodes (default: params/agent.yaml)')
    parser.add_argument('--set', dest='overrides', action='append', default=[],
                        metavar='NODE.PARAM=VALUE', help='parameter override for every session '
                        '(repeatable)')
    parser.add_argument('--parallel', type=int, default=0,
                        help='local pool: sessions at once (default: the CPU count)')
    parser.add_argument('--ray', action='store_true',
                        help='run the tasks on a Ray instance started on this machine')
    parser.add_argument('--ray-address', default='',
                        help="run the tasks on an existing Ray cluster: 'auto' or host:port")
    parser.add_argument('--cpus-per-session', type=float, default=1.0,
                        help='Ray: CPUs each session task declares (default 1)')
    parser.add_argument('--checkpoints', action='store_true',
                        help='in-process engine: write the agent checkpoints of every session '
                        '(default off: a sweep does not resume, and they cost time)')
    parser.add_argument('--stop-after', type=float, default=0.0, metavar='MINUTES',
                        help='start no session after this many minutes (the sessions running '
                        'then finish; the others are listed as skipped); 0 = none')
    parser.add_argument('--resume', action='store_true',
                        help='run only the sessions no earlier run of this --name finished '
                        '(same settings and engine; its bag folder kept); default: run all')
    parser.add_argument('--pull-bags', action='store_true',
                        help='workers send their session folders back to this machine (no '
                        'shared filesystem); default: they write to --bags-dir directly')
    parser.add_argument('--params-dir', default='',
                        help='parameter files (default: ./params in a checkout, else the '
                        'installed ones)')
    parser.add_argument('--name', default='', help='experiment name (default: the time)')
    parser.add_argument('--bags-dir', default='bags', help='root of the bags (default bags)')
    parser.add_argument('--runs-dir', default='runs', help='root of logs and reports')
    parser.add_argument('--report-out', default='',
                        help='where the study writes results.md (default '
                        '<runs-dir>/<name>/report)')
    parser.add_argument('--no-report', dest='report', action='store_false',
                        help='skip the study at the end')
    return parser
