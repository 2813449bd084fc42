#!/usr/bin/env python3
"""A returning person: the first episode of a session started from their last one, seed by seed.

For each seed (the simulated person N of the profile's population, as ``hrc experiment`` gives
seed N) and case, in-process sessions with the default learning configuration: the first from a
new policy; then the person comes back and the session starts from the first's final.pt
(``--start-from``, what ``hrc session --study-dir`` does for a subject back for a case they
finished). The person comes back twice, from the same robot:

* **practised**: the simulated person keeps the practice of the first session
  (``human.practiced_episodes`` = the episodes they acted in there), rested (no fatigue) and
  with their judged horizontal to learn again (the per-episode adaptation starts over). A
  modelling choice with a source: continuous tracking skill is retained almost whole over
  months without practice (Fleishman & Parker 1962, J. Exp. Psychol. 64(3):215-226; in the
  meta-analysis of Arthur et al. 1998, Human Performance 11(1):57-101, physical and natural
  continuous tasks decay least);
* **new to the task**: the person starts the learning curve again (the bound of full
  forgetting; the only return this bench measured before, bench/README.md at 9c55197).

Printed per case and return, with the median over seeds and a 95% percentile bootstrap
interval (seeded): the team's total error in the second session's first episode over the first
session's evaluation mean (the target: <= 1, "no worse than where their last session ended"),
and the person's episodes of both::

    python bench/returning_person.py --cases 2 6 --seeds 10 --parallel 2
"""

import argparse
import multiprocessing
import pathlib
import statistics
import tempfile

from hrc_common.contract import EpisodeKind
from hrc_common.session_control import FINAL_CHECKPOINT
from hrc_common.session_plan import SessionSettings
from hrc_engine.engine import EngineConfig, SummariesSession
from hrc_study.statistics import bootstrap_interval
import numpy

# how the person comes back: True keeps the first session's practice (module docstring)
RETURNS = {'practised': True, 'new to the task': False}


def run(case: int, seed: int, runs: pathlib.Path, session_id: str, start_from: str = '',
        practiced_episodes: int = 0):
    """Run one session (no bags); return its episode summaries.

    ``practiced_episodes``: the simulated person's practice before the session.
    """
    session = SummariesSession(EngineConfig(SessionSettings(
        case=case, seed=seed, session_id=session_id, record=False, runs_dir=str(runs),
        start_from=start_from,
        overrides={'human.practiced_episodes': int(practiced_episodes)})))
    session.run()
    return session.summaries


def person_episodes(summaries) -> int:
    """Return the human-involved training and judging episodes."""
    return sum(1 for item in summaries if item['human_involved']
               and item['kind'] in (EpisodeKind.TRAINING, EpisodeKind.JUDGING))


def acted(summaries) -> int:
    """Return the episodes the person acted in (training, judging and evaluation)."""
    return sum(1 for item in summaries if item['human_involved'])


def pair(task: tuple) -> dict:
    """Return, for one person back for one case: {return: ratio} and the person's episodes.

    ``task``: (case, seed, the folder of the sessions' runs).
    """
    case, seed, runs = task
    first = run(case, seed, runs, f'case{case}-seed{seed}-first')
    evaluation = [item['total_error'] for item in first
                  if item['kind'] == EpisodeKind.EVALUATION]
    checkpoint = runs / 'checkpoints' / f'case{case}-seed{seed}-first' / FINAL_CHECKPOINT
    result = {'first_session': person_episodes(first)}
    for name, practice in RETURNS.items():
        session_id = f"case{case}-seed{seed}-{name.replace(' ', '-')}"
        second = run(case, seed, runs, session_id, str(checkpoint),
                     acted(first) if practice else 0)
        result[name] = second[0]['total_error'] / statistics.mean(evaluation)
        result[f'{name}_back'] = person_episodes(second)
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--cases', type=int, nargs='+', default=[2, 6])
    parser.add_argument('--seeds', type=int, default=5, help='persons 0..N-1 (default 5)')
    parser.add_argument('--parallel', type=int, default=1, help='people at once (default 1)')
    args = parser.parse_args(argv)
    if min(args.seeds, args.parallel) < 1:
        parser.error('--seeds and --parallel must be >= 1')
    print('| case | the person comes back | seeds | first episode back / last evaluation, '
          "median [95% CI] | worst | person's episodes: first session / back, medians |")
    print('|---|---|---|---|---|---|')
    with tempfile.TemporaryDirectory() as folder, \
            multiprocessing.get_context('spawn').Pool(args.parallel) as pool:
        for case in args.cases:
            results = pool.map(pair, [(case, seed, pathlib.Path(folder))
                                      for seed in range(args.seeds)])
            for name in RETURNS:
                ratios = [result[name] for result in results]
                interval = bootstrap_interval(ratios, numpy.median)
                print(f'| {case} | {name} | {args.seeds} | {interval.estimate:.2f} '
                      f'[{interval.low:.2f}, {interval.high:.2f}] | {max(ratios):.2f} | '
                      f"{statistics.median(r['first_session'] for r in results):g} / "
                      f"{statistics.median(r[f'{name}_back'] for r in results):g} |",
                      flush=True)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
