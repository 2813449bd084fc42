#!/usr/bin/env python3
"""A returning person: the first episode of a session started from their last one, seed by seed.

For each seed (the simulated person N of the profile's population, as ``hrc experiment`` gives
seed N) and case, two in-process sessions with the default learning configuration: the first
from a new policy; the second from the first's final.pt (``--start-from``, what ``hrc session
--study-dir`` does for a subject back for a case they finished). Printed per case, with the
median over seeds and a 95% percentile bootstrap interval (seeded): the team's total error in
the second session's first episode over the first session's evaluation mean (the target:
<= 1, "no worse than where their last session ended"), and the person's episodes of both::

    python bench/returning_person.py --cases 2 6 --seeds 5
"""

import argparse
import pathlib
import statistics
import tempfile

from hrc_common.contract import EpisodeKind
from hrc_common.session_control import FINAL_CHECKPOINT
from hrc_common.session_plan import SessionSettings
from hrc_engine.engine import EngineConfig, SummariesSession
from hrc_study.statistics import bootstrap_interval
import numpy


def run(case: int, seed: int, runs: pathlib.Path, session_id: str, start_from: str = ''):
    """Run one session (no bags); return its episode summaries."""
    session = SummariesSession(EngineConfig(SessionSettings(
        case=case, seed=seed, session_id=session_id, record=False, runs_dir=str(runs),
        start_from=start_from)))
    session.run()
    return session.summaries


def person_episodes(summaries) -> int:
    """Return the human-involved training and judging episodes."""
    return sum(1 for item in summaries if item['human_involved']
               and item['kind'] in (EpisodeKind.TRAINING, EpisodeKind.JUDGING))


def pair(case: int, seed: int, runs: pathlib.Path) -> tuple:
    """Return (ratio, person's episodes first, second) of one person back for one case."""
    first = run(case, seed, runs, f'case{case}-seed{seed}-first')
    evaluation = [item['total_error'] for item in first
                  if item['kind'] == EpisodeKind.EVALUATION]
    checkpoint = runs / 'checkpoints' / f'case{case}-seed{seed}-first' / FINAL_CHECKPOINT
    second = run(case, seed, runs, f'case{case}-seed{seed}-second', str(checkpoint))
    return (second[0]['total_error'] / statistics.mean(evaluation), person_episodes(first),
            person_episodes(second))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--cases', type=int, nargs='+', default=[2, 6])
    parser.add_argument('--seeds', type=int, default=5)
    args = parser.parse_args(argv)
    print('| case | seeds | first episode back / last evaluation, median [95% CI] | worst | '
          "person's episodes: first session / back, medians |")
    print('|---|---|---|---|---|')
    with tempfile.TemporaryDirectory() as folder:
        for case in args.cases:
            results = [pair(case, seed, pathlib.Path(folder)) for seed in range(args.seeds)]
            ratios = [ratio for ratio, _, _ in results]
            interval = bootstrap_interval(ratios, numpy.median)
            print(f'| {case} | {args.seeds} | {interval.estimate:.2f} [{interval.low:.2f}, '
                  f'{interval.high:.2f}] | {max(ratios):.2f} | '
                  f'{statistics.median(first for _, first, _ in results):g} / '
                  f'{statistics.median(back for _, _, back in results):g} |', flush=True)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
