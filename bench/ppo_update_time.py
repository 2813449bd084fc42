"""PPO update time per iteration on this machine (horizon 512, 3 epochs, minibatch 64).

    python bench/ppo_update_time.py [--iterations 20] [--threads 1 2]

Fills a rollout buffer with 512 samples of 200-step episodes (random observations, actions
from the policy, Gaussian rewards: the update's cost does not depend on their values), then
times ``PPO.update`` (24 minibatches of 64: forward, backward, clip, Adam) per iteration and the
per-step action selection. Table I settings and the default 2 x 64 tanh networks.
"""

import argparse
import statistics
import sys
import time

import numpy as np
import torch

from hrc_agent_node.config import AgentParams
from hrc_agent_node.ppo import PPO, RolloutBuffer
from hrc_common.params import with_overrides


def fill(learner, rng, samples):
    """Return a buffer of ``samples`` samples in 200-step episodes."""
    buffer = RolloutBuffer()
    while len(buffer) < samples:
        length = min(200, samples - len(buffer))
        observations = rng.normal(size=(length, learner.observation_size)).astype(np.float32)
        acted = [learner.act(observation) for observation in observations]
        buffer.add_episode(observations, [a[0] for a in acted], [a[2] for a in acted],
                           [a[3] for a in acted], rng.normal(size=length), 0.0, False,
                           0.995, 0.95)
    return buffer


def main(argv=None) -> int:
    """Print the timing table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--iterations', type=int, default=20)
    parser.add_argument('--threads', type=int, nargs='+', default=[1, 2])
    args = parser.parse_args(argv)
    params = with_overrides(AgentParams(), horizon=512, epochs=3, minibatch_size=64)
    rng = np.random.default_rng(0)
    print(f'torch {torch.__version__}, horizon {params.horizon}, epochs {params.epochs}, '
          f'minibatch {params.minibatch_size}, networks {params.hidden_layers} x '
          f'{params.hidden_size} tanh')
    for threads in args.threads:
        learner = PPO(7, with_overrides(params, torch_threads=threads), seed=0)
        torch.set_num_threads(threads)
        times = []
        for _ in range(args.iterations + 1):
            buffer = fill(learner, rng, params.horizon)
            start = time.perf_counter()
            learner.update(buffer)
            times.append(time.perf_counter() - start)
        times = times[1:]  # the first iteration warms up torch
        observation = rng.normal(size=7).astype(np.float32)
        start = time.perf_counter()
        for _ in range(2000):
            learner.act(observation)
        act_us = (time.perf_counter() - start) / 2000 * 1e6
        print(f'threads {threads}: update {statistics.mean(times) * 1000:.1f} ms mean, '
              f'{statistics.median(times) * 1000:.1f} ms median, {max(times) * 1000:.1f} ms max '
              f'({args.iterations} iterations); action selection {act_us:.0f} us per step')
    return 0


if __name__ == '__main__':
    sys.exit(main())
