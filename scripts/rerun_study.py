#!/usr/bin/env python3
r"""Rerun the study: cases x seeds in the engine, a graph spot check, the results.

The paper's cases x seeds run through the in-process engine, a graph spot check must match the
engine's rows exactly, then docs/results.md is written from the run.

Steps, each printed as it starts:

1. refuse a work tree with uncommitted source changes (the results must come from a commit;
   ``--allow-dirty`` runs anyway and says so in the results' note);
2. for each learning configuration (``--learnings``: params/learning/<name>.yaml; default the
   session default ``sac`` and ``ppo``, the paper's algorithm with the study's rules):
   ``experiment``
   of every case of params/cases.yaml (the paper's six and the two partners-first cases) with
   the ``paper`` profile (``--seeds`` seeds, person N of its population for seed N) and the
   ``paper_symmetric`` control (``--control-seeds``), in-process, ``--parallel`` at once;
3. the spot check: the sessions of ``--spot-check`` (case:seed; default case 2 seed 0, case 4
   seed 1 and the partners-first case 8 seed 0) rerun through the ROS graph (the nodes over
   DDS), and every episode of each compared with the engine's: the same returns, errors,
   efforts and kinds, or the rerun fails (exit 1);
4. once every configuration has run: ``hrc_results`` on the default configuration's run into
   ``--out`` (docs/results.md), each other one into ``--out``/<name>.

Example (the whole study: 8 cases x (10 + 5) seeds x 2 configurations, ~3 h on 2 cores)::

    python scripts/rerun_study.py --parallel 2

A run cut short (Ctrl-C, a machine that went down) continues where it stopped with the same
command plus ``--resume``: every session that finished is journalled at once and kept (its
bags, its row), only the others run (``hrc experiment --resume``; a session is kept only if the
same commit ran it). The results then list the runs and sum their wall time.

A small run to try it (two cases, two seeds, no control, PPO only, no spot check)::

    python scripts/rerun_study.py --cases 2 4 --seeds 2 --control-seeds 0 --learnings ppo \
        --spot-check --name try --out /tmp/try-results --allow-dirty

Exit codes: 0 done, 1 a session failed or the spot check differs, 2 bad arguments.
"""

import argparse
import dataclasses
import pathlib
import subprocess
import sys
import time

try:
    from hrc_common.cases import case_ids
    from hrc_bag.report import load_records
    from hrc_common.paths import params_dir
    from hrc_common.session_plan import DEFAULT_LEARNING, learning_names
except ModuleNotFoundError as missing:   # started without the workspace's environment
    print(f'rerun_study: {missing}: run `make setup` once, then `source scripts/env.sh` in this '
          'shell', file=sys.stderr)
    sys.exit(2)

REPO = pathlib.Path(__file__).resolve().parents[1]


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description=__doc__.split('\n\n')[0], epilog='Example: python scripts/rerun_study.py '
        '--parallel 2', formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--cases', type=int, nargs='+', default=list(case_ids()),
                        help='cases (default: every case of params/cases.yaml, '
                        f'{" ".join(map(str, case_ids()))})')
    parser.add_argument('--seeds', type=int, default=10, help='seeds of the paper profile')
    parser.add_argument('--control-seeds', type=int, default=5,
                        help='seeds of the paper_symmetric control (0: none)')
    parser.add_argument('--learnings', nargs='+', default=[DEFAULT_LEARNING, 'ppo'],
                        choices=learning_names(params_dir()), metavar='NAME',
                        help='learning configurations (params/learning/<name>.yaml; default '
                        f'{DEFAULT_LEARNING} ppo)')
    parser.add_argument('--episodes', type=int, default=300, help='episode limit per session')
    parser.add_argument('--spot-check', nargs='*', default=['2:0', '4:1', '8:0'],
                        metavar='CASE:SEED',
                        help='sessions rerun through the graph and compared (none: no check)')
    parser.add_argument('--parallel', type=int, default=2, help='sessions at once')
    parser.add_argument('--stop-after', type=float, default=0.0, metavar='MINUTES',
                        help="each configuration's experiment starts no session after this many "
                        'minutes; a cut run holds whole seeds (every case) of each profile '
                        '(default 0 = none)')
    parser.add_argument('--name', default='study-rerun', help='experiment name (bags/<name>)')
    parser.add_argument('--bags-dir', default=str(REPO / 'bags'))
    parser.add_argument('--runs-dir', default=str(REPO / 'runs'))
    parser.add_argument('--out', default=str(REPO / 'docs'), help='folder of results.md')
    parser.add_argument('--resume', action='store_true',
                        help='keep the sessions an earlier run of the same --name finished; '
                        'run only the others (hrc experiment --resume)')
    parser.add_argument('--allow-dirty', action='store_true',
                        help='run from a work tree with uncommitted changes (said in the note)')
    options = parser.parse_args(argv)
    reasons = []
    if options.seeds < 1:
        reasons.append(f'--seeds must be >= 1, got {options.seeds}')
    if options.control_seeds < 0:
        reasons.append(f'--control-seeds must be >= 0, got {options.control_seeds}')
    if options.parallel < 1:
        reasons.append(f'--parallel must be >= 1, got {options.parallel}')
    if options.stop_after < 0:
        reasons.append(f'--stop-after must be >= 0, got {options.stop_after}')
    spots = []
    for text in options.spot_check:
        case, _, seed = text.partition(':')
        if not (case.isdigit() and seed.isdigit()):
            reasons.append(f'--spot-check {text!r}: expected CASE:SEED, e.g. 2:0')
            continue
        spots.append((int(case), int(seed)))
        if int(seed) >= options.seeds:
            reasons.append(f'--spot-check {text}: seed {seed} is not run (--seeds '
                           f'{options.seeds})')
        if options.cases and int(case) not in options.cases:
            reasons.append(f'--spot-check {text}: case {case} is not run')
    if reasons:
        parser.error('\n  '.join([''] + reasons))
    options.spots = spots
    return options


def uncommitted() -> list:
    """Return the tracked files that differ from HEAD (untracked files do not count)."""
    result = subprocess.run(['git', 'status', '--porcelain', '--untracked-files=no'], cwd=REPO,
                            capture_output=True, text=True, check=False)
    return [line[3:] for line in result.stdout.splitlines() if line.strip()]


def commit() -> str:
    result = subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], cwd=REPO,
                            capture_output=True, text=True, check=False)
    return result.stdout.strip() or 'unknown'


def experiment(options, name: str, learning: str, extra: list) -> int:
    """Run one ``experiment`` (in-process unless ``extra`` says otherwise); return its code."""
    command = [sys.executable, '-m', 'hrc_bringup.experiment', '--episodes',
               str(options.episodes), '--parallel', str(options.parallel), '--name', name,
               '--bags-dir', options.bags_dir, '--runs-dir', options.runs_dir, '--no-report',
               '--learning', learning]
    if options.cases and '--cases' not in extra:
        command += ['--cases'] + [str(case) for case in options.cases]
    if options.resume:
        command += ['--resume']
    command += extra
    print('[rerun] ' + ' '.join(command[2:]), flush=True)
    return subprocess.run(command, check=False).returncode


def episode_rows(folder: pathlib.Path) -> dict:
    """Return {(case, seed): [episode record as a dict]} of the paper sessions of a run."""
    rows = {}
    for record in load_records([str(folder)], log=lambda text: None):
        if record.profile == 'paper':
            rows[(record.case_id, record.seed)] = [dataclasses.asdict(episode)
                                                   for episode in record.episodes]
    return rows


def spot_check(options, learning: str, engine_folder: pathlib.Path) -> list:
    """Rerun the spot-check sessions through the graph; return every difference found."""
    engine = episode_rows(engine_folder)
    problems = []
    for case, seed in options.spots:
        name = f'{options.name}-{learning}-graph-case{case}-seed{seed}'
        code = experiment(options, name, learning,
                          ['--engine', 'graph', '--cases', str(case), '--first-seed', str(seed),
                           '--seeds', '1', '--profiles', 'paper', '--parallel', '1'])
        if code != 0:
            problems.append(f'case {case} seed {seed}: the graph session exited {code}')
            continue
        graph = episode_rows(pathlib.Path(options.bags_dir) / name)
        mine, theirs = graph.get((case, seed)), engine.get((case, seed))
        if mine is None or theirs is None:
            problems.append(f'case {case} seed {seed}: missing from the '
                            f'{"graph" if mine is None else "engine"} run')
        elif mine != theirs:
            first = next((i for i, (a, b) in enumerate(zip(mine, theirs)) if a != b),
                         min(len(mine), len(theirs)))
            problems.append(f'case {case} seed {seed}: graph and engine differ from episode '
                            f'{first} ({len(mine)} vs {len(theirs)} episodes)')
        else:
            print(f'[rerun] spot check case {case} seed {seed} ({learning}): graph == engine, '
                  f'{len(mine)} episodes identical', flush=True)
    return problems


def main(argv=None) -> int:
    options = parse_arguments(argv)
    dirty = uncommitted()
    if dirty and not options.allow_dirty:
        print('rerun_study: the work tree has uncommitted changes (commit them, or run with '
              '--allow-dirty):\n  ' + '\n  '.join(dirty), file=sys.stderr)
        return 2
    started = time.monotonic()
    version = commit() + ('-dirty' if dirty else '')
    profiles = ['--profiles', f'paper:{options.seeds}'] + (
        [f'paper_symmetric:{options.control_seeds}'] if options.control_seeds else [])
    failures = []
    finished = []     # (learning, its bags folder, minutes of this run when it was done)
    for learning in options.learnings:
        name = f'{options.name}-{learning}'
        code = experiment(options, name, learning, ['--seeds', str(options.seeds),
                                                   '--stop-after', str(options.stop_after)]
                          + profiles)
        if code != 0:
            failures.append(f'{learning}: the experiment exited {code}')
            continue
        folder = pathlib.Path(options.bags_dir) / name
        failures += [f'{learning}: {problem}'
                     for problem in spot_check(options, learning, folder)]
        finished.append((learning, folder, (time.monotonic() - started) / 60.0))
    # The pages are written once every configuration's sessions have run: pages written into
    # the work tree between two configurations made the next one's sessions record a "-dirty"
    # version, which a --resume of that configuration then refused to keep.
    for learning, folder, minutes in finished:
        out = pathlib.Path(options.out) / ('' if learning == DEFAULT_LEARNING else learning)
        note = (f'Rerun by scripts/rerun_study.py at git {version}'
                f'{" (resumed: see the runs above)" if options.resume else ""}, learning '
                f'configuration {learning} (params/learning/{learning}.yaml); '
                f'{minutes:.1f} min wall in this run so far on this machine; graph spot check '
                f'{" ".join(options.spot_check) or "none"}.')
        command = [sys.executable, '-m', 'hrc_study.results_cli', str(folder), '--out',
                   str(out), '--note', note]
        print('[rerun] ' + ' '.join(command[2:4]) + ' --out ' + str(out), flush=True)
        if subprocess.run(command, check=False).returncode != 0:
            failures.append(f'{learning}: hrc_results failed')
    minutes = (time.monotonic() - started) / 60.0
    print(f'[rerun] {len(options.learnings)} configuration(s) in {minutes:.1f} min wall at git '
          f'{version}' + (': ' + '; '.join(failures) if failures else ': done'), flush=True)
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
