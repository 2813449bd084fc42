#!/usr/bin/env python3
"""What the partner model costs inside the 0.2 s control step, measured in one run.

The robot's decision per step (AgentCore.act: the observation, with the partner model fitted
when ``partner_inference`` is on, and the SAC actor's forward pass; deterministic, no learning)
is timed with and without the partner model, alternating rounds of whole episodes on the real
PyBullet sim with the simulated person of profile ``paper``. Printed: the median time of a
decision each way, their ratio, and the share of the 0.2 s period the partner model takes::

    python bench/partner_inference_cost.py --rounds 6 --episodes 2
"""

import argparse
import statistics
import time

import torch

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common.contract import Phase, SimLimits
from hrc_common.params import with_overrides
from hrc_common.paths import params_dir
from hrc_common.session_plan import load_learning
from hrc_engine.offline import make_partner, run_episode
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

PERIOD_S = 0.2


class TimedCore(AgentCore):
    """An AgentCore that keeps the wall time of each act() call."""

    def __init__(self, params, limits):
        super().__init__(params, limits=limits)
        self.seconds = []

    def act(self, state, human_action=None):
        started = time.perf_counter()
        decision = super().act(state, human_action)
        self.seconds.append(time.perf_counter() - started)
        return decision


def decision_seconds(partner_inference: bool, episodes: int, seed: int) -> list:
    """Return the act() times of ``episodes`` deterministic episodes of case 5 (person acts)."""
    learning = load_learning(params_dir(), 'partner_aware')
    learning.update(partner_inference=partner_inference, max_training_episodes=1)
    params = with_overrides(AgentParams(), **learning, case=5, seed=seed,
                            evaluation_episodes=episodes, checkpoint_dir='', torch_threads=1)
    physics = PhysicsParams()
    core = TimedCore(params, SimLimits.of(physics))
    core.phase = Phase.EVALUATION          # the frozen policy: decisions only, no learning
    partner = make_partner(core, kind='human:paper', seed=seed, limits=SimLimits.of(physics))
    with SliderPendulumBall(physics) as sim:
        for _ in range(episodes):
            run_episode(core, sim, partner)
    return core.seconds


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--rounds', type=int, default=6)
    parser.add_argument('--episodes', type=int, default=2)
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    times = {False: [], True: []}
    for round_index in range(args.rounds):
        for inference in ((False, True) if round_index % 2 == 0 else (True, False)):
            times[inference] += decision_seconds(inference, args.episodes, round_index)
    plain, aware = (statistics.median(times[key]) * 1e3 for key in (False, True))
    print(f'decisions timed: {len(times[False])} without, {len(times[True])} with the model')
    print(f'median decision: {plain:.3f} ms without the partner model, {aware:.3f} ms with it '
          f'(ratio {aware / plain:.2f}); the model adds {aware - plain:.3f} ms, '
          f'{100 * (aware - plain) / 1e3 / PERIOD_S:.3f}% of the {PERIOD_S:g} s period')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
