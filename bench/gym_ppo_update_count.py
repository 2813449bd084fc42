"""Why SB3 reached the whole-task criterion sooner: PPO updates per episode (an experiment).

    python bench/gym_ppo_update_count.py --data docs/gym/ppo_comparison.json --seeds 0 1 2 3 4

With Table I's horizon of 512 steps, SB3 updates every 512 steps (2.56 episodes), ours at the
first episode end with at least 512 samples (every 3 episodes). With the small clip (0.05)
each update can move the policy only a little, so the number of updates may matter more than
the samples in each. This prints the episodes to the criterion of each run of the comparison
converted to the PPO updates done by then, and trains ours once more with ``--horizon``
(default 400: an update every 2 episodes, more often than SB3) on the whole task, seeds as
given, printing its episodes to the criterion and updates.
"""

import argparse
import json
import sys

import numpy as np

from hrc_gym.compare import episodes_to_criterion, make_env, train_ours

STEPS_PER_EPISODE = 200


def updates_before(learner: str, episodes: int, horizon: int) -> int:
    """Return the PPO updates a learner has done after ``episodes`` training episodes."""
    if learner == 'sb3':
        return episodes * STEPS_PER_EPISODE // horizon
    per_update = -(-horizon // STEPS_PER_EPISODE)  # episodes until the buffer holds a horizon
    return episodes // per_update


def main(argv=None) -> int:
    """Convert the comparison's criterion episodes to updates; train ours with another horizon."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--data', default='docs/gym/ppo_comparison.json')
    parser.add_argument('--seeds', nargs='+', type=int, default=[0, 1, 2, 3, 4])
    parser.add_argument('--episodes', type=int, default=200)
    parser.add_argument('--horizon', type=int, default=400)
    args = parser.parse_args(argv)

    with open(args.data) as stream:
        results = json.load(stream)
    for setting, runs in results['runs'].items():
        env = make_env(setting)
        try:
            for learner, seeds in runs.items():
                reached = {seed: episodes_to_criterion(env, records)
                           for seed, records in sorted(seeds.items())}
                updates = [updates_before(learner, value, 512) for value in reached.values()
                           if value is not None]
                print(f'{setting} {learner} horizon 512: episodes {list(reached.values())}, '
                      f'updates {updates}, median updates '
                      f'{np.median(updates) if updates else "-"}', flush=True)
        finally:
            env.close()
    env = make_env('whole')
    try:
        reached = []
        for seed in args.seeds:
            records = train_ours('whole', seed, args.episodes, horizon=args.horizon)
            reached.append(episodes_to_criterion(env, records))
            print(f'whole ours horizon {args.horizon} seed {seed}: episodes {reached[-1]}, '
                  f'last-20 return {np.mean([r["return"] for r in records[-20:]]):.1f}',
                  flush=True)
    finally:
        env.close()
    done = [value for value in reached if value is not None]
    print(f'whole ours horizon {args.horizon}: episodes {reached} (median '
          f'{np.median(done) if done else "-"}), updates '
          f'{[updates_before("ours", value, args.horizon) for value in done]}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
