"""crossplay: evaluate trained agents with partners they may never have met; write the matrix.

    hrc partners crossplay \
        --agent one=runs/partners/c2-one-s0.pt pop=runs/partners/c2-population-s0.pt \
        --partner profile:novice profile:skilled person:paper:100000 model:models/alice.pt \
        --seeds 0 1 2 --episodes 3 --out runs/crossplay

Agents: ``NAME=CHECKPOINT[@TRAINING_PARTNER]`` (the training partner also comes from the
``.json`` that ``train_partners_agents`` writes beside the checkpoint; it is added as a column
and each agent's drop is measured from it). Partners: ``profile:NAME``, ``person:NAME:K``,
``population:NAME``, ``model:PATH`` (hrc_engine.partners). Writes ``matrix.json`` (every
seed's error), ``matrix.md`` (mean [95 % interval] and drops) and ``heatmap.png`` to --out and
prints the Markdown. On stderr, a line per cell with the time left (a bar on a terminal, plain
lines when piped; none with --quiet). Exit 2 with every reason for bad input.
"""

import argparse
import pathlib
import sys

from hrc_common.params import ParameterError
from hrc_common.time_left import TimeLeft


def cell_count(agents, partners) -> int:
    """Return how many cells ``crossplay.run_matrix`` evaluates.

    Each agent's training partner is added as a column when it is not among ``partners``.
    """
    from hrc_partners.crossplay import matrix_columns  # lazy: torch and PyBullet, as in main
    return len(agents) * len(matrix_columns(agents, partners))


def main(argv=None) -> int:
    """Console entry point."""
    parser = argparse.ArgumentParser(prog='hrc partners crossplay',
                                     description=__doc__.split('\n\n')[0])
    parser.add_argument('--agent', nargs='+', required=True, metavar='NAME=CHECKPOINT',
                        help='agents to evaluate (NAME=CHECKPOINT[@TRAINING_PARTNER])')
    parser.add_argument('--partner', nargs='+', required=True, metavar='SPEC',
                        help='partners: profile:NAME, person:NAME:K, population:NAME, '
                             'model:PATH')
    parser.add_argument('--seeds', nargs='+', type=int, default=[0, 1, 2],
                        help='evaluation seeds of every cell')
    parser.add_argument('--episodes', type=int, default=3, help='evaluation episodes per seed')
    parser.add_argument('--profiles-file', default=None,
                        help='simulated-human profiles (default: the installed sim_human.yaml)')
    parser.add_argument('--out', default='runs/crossplay',
                        help='folder for matrix.json, matrix.md and heatmap.png')
    parser.add_argument('--quiet', action='store_true',
                        help='no line per cell (nor the time left) on stderr')
    args = parser.parse_args(argv)

    # after the parsing: these load torch (seconds), --help and usage errors answer without
    from hrc_partners import crossplay  # lazy: torch, PyBullet (seconds): not for --help
    from hrc_engine.partners import spec_problem  # lazy: torch, as above

    problems = []
    if args.episodes < 1:
        problems.append(f'--episodes: expected >= 1, got {args.episodes}')
    if any(seed < 0 for seed in args.seeds):
        problems.append(f'--seeds: expected seeds >= 0, got {args.seeds}')
    if args.profiles_file and not pathlib.Path(args.profiles_file).is_file():
        problems.append(f'--profiles-file: no such file {args.profiles_file}')
    problems += [problem for problem in map(spec_problem, args.partner) if problem]
    try:
        agents = crossplay.parse_agents(args.agent)
    except ParameterError as error:
        problems += error.reasons
    if problems:
        for problem in problems:
            print(f'crossplay: {problem}', file=sys.stderr)
        return 2
    progress, log = None, None
    if not args.quiet:
        progress = TimeLeft(cell_count(agents, args.partner), 'cells', stream=sys.stderr)
        cells_done = []

        def log(line):
            cells_done.append(line)
            progress.show(len(cells_done), f'crossplay: {line}')
    try:
        matrix = crossplay.run_matrix(agents, args.partner, args.seeds, args.episodes,
                                      args.profiles_file, log=log)
    except (ParameterError, ValueError) as error:
        print(f'crossplay: {error}', file=sys.stderr)
        return 2
    finally:
        if progress is not None:
            progress.close()
    paths = crossplay.write_outputs(matrix, args.out)
    print(crossplay.markdown(matrix))
    print('written: ' + ', '.join(paths))
    return 0


if __name__ == '__main__':
    sys.exit(main())
