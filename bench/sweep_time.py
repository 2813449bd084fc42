#!/usr/bin/env python3
"""Benchmark: wall time of a cases x seeds sweep with the in-process engine (bags written).

    python bench/sweep_time.py --cases 1 2 3 4 5 6 --seeds 10 --workers 2   # any directory

Each session is ``hrc_engine.engine.run_session`` with the session's parameter files (the
defaults: up to 60 training episodes and 5 evaluation episodes of 200 steps), run by a local
pool of ``--workers`` processes (each pays the imports once). Prints the wall time of the
sweep, the CPU seconds it used, and the load average, so that a run on a busy machine can be
told from one on a quiet machine (CPU seconds / cores is the wall time the sweep needs when it
has the cores to itself). The graph's wall time for the same sweep is estimated from
``--graph-sample`` sessions run with ``session`` (0 = skip; each takes minutes).
"""

import argparse
import concurrent.futures
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

from hrc_common.cases import paper_case_ids
from hrc_common.executables import executable_path
from hrc_common.session_plan import SessionSettings
from hrc_engine.engine import EngineConfig, run_session


def one_session(case: int, seed: int, work: str) -> tuple:
    """Run one session in this worker; return (case, seed, steps, wall s, evaluation error)."""
    started = time.perf_counter()
    # the parameter files: hrc_common.paths.params_dir() (this checkout's params/ in a checkout)
    result = run_session(EngineConfig(SessionSettings(
        case=case, seed=seed, session_id=f'case{case}-seed{seed}',
        bags_dir=os.path.join(work, 'bags'), runs_dir=os.path.join(work, 'runs'))))
    return (case, seed, result.steps, time.perf_counter() - started,
            result.evaluation.get('total_error', float('nan')))


def graph_session_seconds(case: int, seed: int, work: pathlib.Path, domain_id: int) -> float:
    """Return the wall time of one lockstep graph session (``session``, bags recorded)."""
    command = [str(executable_path('hrc_bringup', 'hrc')),
               'session', '--case', str(case), '--seed',
               str(seed), '--domain-id', str(domain_id), '--no-report', '--bags-dir',
               str(work / 'graph-bags'), '--runs-dir', str(work / 'graph-runs'),
               '--session-id', f'graph-case{case}-seed{seed}']
    started = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, cwd=work)
    if done.returncode != 0:
        raise RuntimeError(f'graph session failed:\n{done.stdout}\n{done.stderr}')
    return time.perf_counter() - started


def cpu_seconds() -> float:
    """Return the CPU seconds of this process and its finished children."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def main() -> int:
    """Run the sweep and print its timing."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--cases', type=int, nargs='+', default=list(paper_case_ids()))
    parser.add_argument('--seeds', type=int, default=10)
    parser.add_argument('--workers', type=int, default=os.cpu_count() or 1)
    parser.add_argument('--graph-sample', type=int, default=0,
                        help='graph sessions to time for the estimate (0 = none)')
    parser.add_argument('--domain-id', type=int, default=93)
    args = parser.parse_args()

    jobs = [(case, seed) for seed in range(args.seeds) for case in args.cases]
    print(f'machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}; {len(jobs)} '
          f'sessions ({len(args.cases)} cases x {args.seeds} seeds), {args.workers} worker '
          f'processes, in-process engine with bags', flush=True)
    with tempfile.TemporaryDirectory(prefix='hrc-sweep-') as work:
        cpu_before, started = cpu_seconds(), time.perf_counter()
        results = []
        with concurrent.futures.ProcessPoolExecutor(args.workers) as pool:
            futures = [pool.submit(one_session, case, seed, work) for case, seed in jobs]
            for future in concurrent.futures.as_completed(futures):
                results.append(future.result())
        wall = time.perf_counter() - started
        cpu = cpu_seconds() - cpu_before
        steps = sum(result[2] for result in results)
        print(f'engine sweep: {wall:.0f} s wall ({wall / 60:.1f} min), {cpu:.0f} CPU s, '
              f'{steps} control steps ({steps / wall:.0f} steps/s in all); per session: median '
              f'{statistics.median(r[3] for r in results):.1f} s wall in its worker')
        print(f'engine sweep on {os.cpu_count()} free cores (CPU s / cores): '
              f'{cpu / (os.cpu_count() or 1) / 60:.1f} min; load average at the end '
              f'{os.getloadavg()[0]:.1f}')
        if args.graph_sample:
            sample = jobs[:args.graph_sample]
            seconds = [graph_session_seconds(case, seed, pathlib.Path(work), args.domain_id)
                       for case, seed in sample]
            estimate = statistics.mean(seconds) * len(jobs) / args.workers
            print(f'graph: {len(sample)} session(s) {", ".join(f"{s:.0f}" for s in seconds)} s '
                  f'wall -> the sweep with {args.workers} sessions at a time: about '
                  f'{estimate / 60:.0f} min (if parallel sessions did not slow each other)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
