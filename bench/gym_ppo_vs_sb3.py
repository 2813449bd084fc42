"""Cross-check: this project's PPO beside Stable-Baselines3's PPO, Table I, same env and seeds.

    python bench/gym_ppo_vs_sb3.py --seeds 0 1 2 3 4 --episodes 200 --out docs/gym

For each setting of ``hrc_gym.compare.SETTINGS`` (case 2's first step, the robot alone; the
whole task with the simulated human) and each seed, trains both learners for ``--episodes``
training episodes, one run after the other in this process (one core), appending each run to
``<out>/ppo_comparison.json`` as it finishes (a run already there is not repeated). Then
draws ``<out>/ppo_comparison.png`` (per setting: the mean return of each learner over the
seeds, a band from the lowest to the highest seed, a 5-episode moving average; the median
episodes to the criterion; a random policy's mean return for reference) and prints, per
learner and setting, the episodes to the strategy's criterion per seed and the mean return of
the first and last 20 episodes, with a logrank test on the episodes to the criterion and a
Mann-Whitney test on the final returns.
``--plot-only`` redraws from the JSON.
"""

import argparse
import json
import os
import sys
import time

from hrc_study.statistics import logrank_faster, mann_whitney_less
import numpy as np

from hrc_gym.compare import episodes_to_criterion, make_env, random_returns, train_ours, train_sb3

LEARNERS = ('ours', 'sb3')
LABELS = {'ours': 'this project (AgentCore)', 'sb3': 'Stable-Baselines3 PPO'}
TITLES = {'alone': 'case 2, step 1: robot alone (reward f(S_x)+f(P_z))',
          'whole': 'whole task with the simulated human (case 6)'}
SMOOTHING = 5      # episodes of the moving average in the figure
SUMMARY_WINDOW = 20  # episodes averaged at the start and the end of training
RANDOM_EPISODES = 10


def moving_average(values, width: int) -> np.ndarray:
    """Return the trailing moving average (shorter windows at the start)."""
    values = np.asarray(values, dtype=float)
    cumulative = np.cumsum(np.insert(values, 0, 0.0))
    out = np.empty_like(values)
    for index in range(len(values)):
        first = max(0, index + 1 - width)
        out[index] = (cumulative[index + 1] - cumulative[first]) / (index + 1 - first)
    return out


def summarize(results: dict) -> list:
    """Return printable lines: criterion episodes and return means per learner and setting."""
    lines = []
    for setting in results['runs']:
        env = make_env(setting)
        try:
            random_mean = float(np.mean(results['random'][setting]))
            lines.append(f'{setting}: {TITLES[setting]}; random policy mean return '
                         f'{random_mean:.1f}')
            for learner in LEARNERS:
                runs = results['runs'][setting].get(learner, {})
                if not runs:
                    continue
                criterion = {seed: episodes_to_criterion(env, records)
                             for seed, records in sorted(runs.items())}
                returns = np.array([[r['return'] for r in records]
                                    for records in runs.values()])
                first = returns[:, :SUMMARY_WINDOW].mean(axis=1)
                last = returns[:, -SUMMARY_WINDOW:].mean(axis=1)
                reached = [value for value in criterion.values() if value is not None]
                lines.append(
                    f'  {learner:5s} episodes to criterion per seed {criterion} '
                    f'(reached {len(reached)}/{len(criterion)}'
                    + (f', median of those {np.median(reached):.0f}' if reached else '')
                    + '); '
                    f'mean return first {SUMMARY_WINDOW} {first.mean():.1f} '
                    f'(seeds {first.min():.1f}..{first.max():.1f}), last {SUMMARY_WINDOW} '
                    f'{last.mean():.1f} ({last.min():.1f}..{last.max():.1f}); '
                    f'wall {sum(results["seconds"][setting][learner].values()):.0f} s')
            lines.append('  ' + compare_learners(results, setting, env))
        finally:
            env.close()
    return lines


def compare_learners(results: dict, setting: str, env) -> str:
    """Return one line: logrank (episodes to criterion, censored) and Mann-Whitney (final).

    Both two-sided in effect: each one-sided p-value is given in both directions.
    """
    runs = results['runs'][setting]
    if not all(runs.get(learner) for learner in LEARNERS):
        return 'comparison: needs runs of both learners'
    limit = results['episodes']
    times, events, finals = {}, {}, {}
    for learner in LEARNERS:
        reached = [episodes_to_criterion(env, records) for records in runs[learner].values()]
        times[learner] = [limit if value is None else value for value in reached]
        events[learner] = [value is not None for value in reached]
        finals[learner] = [np.mean([r['return'] for r in records[-SUMMARY_WINDOW:]])
                           for records in runs[learner].values()]
    race = logrank_faster(times['ours'], events['ours'], times['sb3'], events['sb3'])
    final = mann_whitney_less(finals['sb3'], finals['ours'])
    return (f'ours vs sb3: episodes to criterion {race.detail}, logrank p(ours faster) '
            f'{race.p_value:.2f}, p(sb3 faster) {race.p_reverse:.2f}, restricted-mean '
            f'difference {race.effect:+.1f} episodes (+ = ours faster); final return '
            f'{final.detail} (sb3 vs ours), Mann-Whitney p(ours higher) {final.p_value:.2f}, '
            f'p(sb3 higher) {final.p_reverse:.2f}')


def plot(results: dict, path: str) -> None:
    """Draw the learning curves with min-max bands over the seeds, one panel per setting."""
    import matplotlib  # lazy: matplotlib (about 1 s), only when a figure is drawn
    matplotlib.use('Agg')
    from matplotlib import pyplot  # lazy: matplotlib, after use('Agg') (no display)

    settings = list(results['runs'])
    figure, axes = pyplot.subplots(1, len(settings), figsize=(6.2 * len(settings), 4.2),
                                   squeeze=False)
    colors = {'ours': 'tab:blue', 'sb3': 'tab:orange'}
    for axis, setting in zip(axes[0], settings):
        env = make_env(setting)
        env.close()  # only its task description is needed
        for learner in LEARNERS:
            runs = results['runs'][setting].get(learner, {})
            if not runs:
                continue
            curves = np.array([moving_average([r['return'] for r in records], SMOOTHING)
                               for records in runs.values()])
            episodes = np.arange(1, curves.shape[1] + 1)
            axis.plot(episodes, curves.mean(axis=0), color=colors[learner],
                      label=f'{LABELS[learner]} (mean of {len(runs)} seeds)')
            axis.fill_between(episodes, curves.min(axis=0), curves.max(axis=0),
                              color=colors[learner], alpha=0.2)
            reached = [count for count in (episodes_to_criterion(env, records)
                                           for records in runs.values()) if count is not None]
            if reached:
                axis.axvline(float(np.median(reached)), color=colors[learner], ls=':',
                             label=f'median episodes to criterion of the {len(reached)}/'
                                   f'{len(runs)} seeds that reached it')
        axis.axhline(float(np.mean(results['random'][setting])), color='grey', ls='--',
                     label='random policy')
        axis.set_title(TITLES[setting], fontsize=10)
        axis.set_xlabel('training episode (200 steps of 0.2 s)')
        axis.set_ylabel(f'episode return ({SMOOTHING}-episode moving average)')
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8, loc='lower right')
    figure.suptitle("PPO with the paper's Table I settings: bands = lowest to highest seed",
                    fontsize=11)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)


def main(argv=None) -> int:
    """Run (or resume) the comparison, draw the figure, print the summary."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--seeds', nargs='+', type=int, default=[0, 1, 2, 3, 4])
    parser.add_argument('--episodes', type=int, default=200, help='training episodes per run')
    parser.add_argument('--settings', nargs='+', default=['alone', 'whole'],
                        choices=['alone', 'whole'])
    parser.add_argument('--out', default='docs/gym')
    parser.add_argument('--plot-only', action='store_true')
    args = parser.parse_args(argv)
    if args.episodes < SUMMARY_WINDOW:
        print(f'--episodes must be at least {SUMMARY_WINDOW}', file=sys.stderr)
        return 2


    os.makedirs(args.out, exist_ok=True)
    data_path = os.path.join(args.out, 'ppo_comparison.json')
    results = {'episodes': args.episodes, 'runs': {}, 'random': {}, 'seconds': {}}
    if os.path.exists(data_path):
        with open(data_path) as stream:
            results = json.load(stream)
    if not args.plot_only:
        trainers = {'ours': train_ours, 'sb3': lambda *a: train_sb3(*a)[0]}
        for setting in args.settings:
            runs = results['runs'].setdefault(setting, {})
            seconds = results['seconds'].setdefault(setting, {})
            if setting not in results['random']:
                results['random'][setting] = random_returns(setting, 0, RANDOM_EPISODES)
            for seed in args.seeds:
                for learner in LEARNERS:
                    if str(seed) in runs.get(learner, {}):
                        continue
                    started = time.perf_counter()
                    records = trainers[learner](setting, seed, args.episodes)
                    runs.setdefault(learner, {})[str(seed)] = records
                    seconds.setdefault(learner, {})[str(seed)] = time.perf_counter() - started
                    print(f'{setting} {learner} seed {seed}: '
                          f'{seconds[learner][str(seed)]:.0f} s, last return '
                          f'{records[-1]["return"]:.1f}', flush=True)
                    with open(data_path, 'w') as stream:
                        json.dump(results, stream)
    plot(results, os.path.join(args.out, 'ppo_comparison.png'))
    print('\n'.join(summarize(results)))
    return 0


if __name__ == '__main__':
    sys.exit(main())
