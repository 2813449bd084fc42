#!/usr/bin/env python3
"""Benchmark: lockstep control steps per second, full graph over DDS vs one process without ROS.

    python bench/graph_rate.py --episodes 3 --case 2 --repeats 3

Measures, within episodes (PPO updates between episodes excluded in both):

1. in-process: the same pure components stepped in one Python process — physics core,
   AgentCore (policy forward + bookkeeping), SimulatedHuman — no ROS;
2. graph: `session` (sim, agent, human as separate processes over DDS) without the recorder,
   timed by a listener on /hrc/state in this process;
3. graph + recorder: the same with the MCAP recorder, for the recorder overhead.

Prints steps/s (median over episodes) and the ratios. Numbers, not assertions: run it on a quiet
machine and quote medians.
"""

import argparse
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import threading
import time


def in_process_rate(case: int, episodes: int, seed: int) -> float:
    """Return median control steps/s of whole episodes stepped in one process."""
    from hrc_agent_node.agent_core import AgentCore
    from hrc_agent_node.config import AgentParams
    from hrc_agent_node.offline import run_episode
    from hrc_common.params import load_yaml, with_overrides
    from hrc_joystick_node.sim_human import load_profile, SimulatedHuman
    from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

    physics = PhysicsParams()
    params = load_yaml(AgentParams, 'params/agent.yaml', 'agent')
    params = with_overrides(params, case=case, seed=seed, max_training_episodes=episodes + 1,
                            max_force=physics.max_force, max_torque=physics.max_torque,
                            checkpoint_dir='')
    core = AgentCore(params)
    human = SimulatedHuman(load_profile('paper'), core.human_dof, seed=seed)
    rates = []
    with SliderPendulumBall(physics) as sim:
        for episode in range(episodes):
            human.reset(episode)
            start = time.perf_counter()
            result = run_episode(core, sim, human.act)
            rates.append(result.steps / (time.perf_counter() - start))
            if core.phase == 'updating':
                core.update()
    return statistics.median(rates)


class StateTimer:
    """Records the receive time of every /hrc/state message on a domain (own thread)."""

    def __init__(self, domain_id: int):
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor

        from hrc_common import qos, topics
        from hrc_msgs.msg import TaskState

        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node('bench_state_timer', context=self.context)
        self.samples = []  # (episode, step, receive time)
        self.node.create_subscription(TaskState, topics.STATE, self._on_state, qos.STATE_QOS)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _on_state(self, state):
        self.samples.append((state.episode, state.step, time.perf_counter()))

    def _spin(self):
        from rclpy.executors import ExternalShutdownException
        try:
            while self.context.ok():
                self.executor.spin_once(timeout_sec=0.1)
        except ExternalShutdownException:
            pass

    def episode_rates(self) -> list:
        """Return steps/s of every complete episode (first to last state received)."""
        by_episode = {}
        for episode, step, stamp in self.samples:
            by_episode.setdefault(episode, []).append((step, stamp))
        rates = []
        for samples in by_episode.values():
            steps = [step for step, _ in samples]
            if len(samples) > 100:
                times = [stamp for _, stamp in samples]
                rates.append((max(steps) - min(steps)) / (max(times) - min(times)))
        return rates

    def close(self):
        """Stop the listener."""
        import rclpy
        rclpy.shutdown(context=self.context)
        self.thread.join(timeout=5)


def graph_rate(case: int, episodes: int, seed: int, record: bool, domain_id: int) -> dict:
    """Run a session and return {'rate': median steps/s, 'cpu': child CPU s, 'wall': s}."""
    from hrc_common.testing import executable_path

    timer = StateTimer(domain_id)
    work = pathlib.Path(tempfile.mkdtemp(prefix='hrc-bench-'))
    command = [str(executable_path('hrc_bringup', 'session')), '--case', str(case),
               '--seed', str(seed), '--episodes', str(episodes), '--eval-episodes', '0',
               '--domain-id', str(domain_id), '--no-report', '--bags-dir', str(work / 'bags'),
               '--runs-dir', str(work / 'runs'), '--session-id', 'bench']
    if not record:
        command.append('--no-record')
    before = os.times()
    start = time.perf_counter()
    result = subprocess.run(command, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = os.times()
    time.sleep(0.5)
    timer.close()
    if result.returncode != 0:
        raise RuntimeError(f'session failed:\n{result.stdout}\n{result.stderr}')
    rates = timer.episode_rates()
    bag_bytes = sum(path.stat().st_size for path in (work / 'bags').rglob('*.mcap'))
    return {'rate': statistics.median(rates) if rates else float('nan'), 'episodes': len(rates),
            'cpu': (after.children_user + after.children_system)
            - (before.children_user + before.children_system),
            'wall': wall, 'bag_bytes_per_episode': bag_bytes / max(episodes, 1)}


def main() -> int:
    """Run the three measurements and print them with their ratios."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--case', type=int, default=2)
    parser.add_argument('--episodes', type=int, default=3)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--domain-id', type=int, default=91)
    parser.add_argument('--repeats', type=int, default=3, help='rounds of the three runs')
    args = parser.parse_args()

    print(f'machine: {os.cpu_count()} cores, python {sys.version.split()[0]}; case {args.case}, '
          f'{args.episodes} episodes of 200 steps per measurement, {args.repeats} rounds '
          f'(in-process, graph, graph + recorder in turn; ratios pair by pair)', flush=True)
    rounds = []
    for round_index in range(args.repeats):
        local = in_process_rate(args.case, args.episodes, args.seed)
        bare = graph_rate(args.case, args.episodes, args.seed, False, args.domain_id)
        recorded = graph_rate(args.case, args.episodes, args.seed, True, args.domain_id)
        rounds.append((local, bare, recorded))
        print(f'round {round_index + 1}: in-process {local:6.0f} steps/s | graph '
              f'{bare["rate"]:5.0f}'
              f' steps/s (nodes CPU {bare["cpu"]:.1f} s) | graph + recorder '
              f'{recorded["rate"]:5.0f} steps/s (nodes CPU {recorded["cpu"]:.1f} s, '
              f'{recorded["bag_bytes_per_episode"] / 1024:.0f} KiB MCAP per episode)', flush=True)
    median = statistics.median
    local = median(r[0] for r in rounds)
    bare = median(r[1]['rate'] for r in rounds)
    recorded = median(r[2]['rate'] for r in rounds)
    print(f'median in-process (no ROS)      : {local:6.0f} steps/s')
    print(f'median graph over DDS           : {bare:6.0f} steps/s  '
          f'(real-time factor {bare * 0.2:.0f}x)')
    print(f'median graph over DDS + recorder: {recorded:6.0f} steps/s')
    print(f'ratio graph / in-process       : {median(r[1]["rate"] / r[0] for r in rounds):.2f}')
    print(f'recorder overhead (steps/s)    : '
          f'{median(1 - r[2]["rate"] / r[1]["rate"] for r in rounds) * 100:+.1f}%')
    print(f'recorder overhead (nodes CPU)  : '
          f'{median(r[2]["cpu"] / r[1]["cpu"] - 1 for r in rounds) * 100:+.1f}%')
    return 0


if __name__ == '__main__':
    sys.exit(main())
