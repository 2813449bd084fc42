#!/usr/bin/env python3
"""Benchmark: realtime mode, state period jitter and command latency over DDS.

    python bench/realtime_jitter.py --episodes 1

Runs a realtime session (sim, agent, simulated human as separate processes; the sim steps every
0.2 s of wall time) and listens on /hrc/state and both command topics in this process:

* period jitter: |interval between consecutive states - control_period| within episodes,
  p50 / p99 / max (ms);
* command latency: receive time of a command minus receive time of the state it answers (same
  stamp), per actor, p50 / p99 (ms). Both ends are measured in this process, so clocks agree.

Only realtime episodes are measured, whatever the case: an episode whose states came faster
than half the control period ran in lockstep (in case 2 the robot's episodes alone do) and is
left out, and the count of such episodes is printed; with none left the bench says so and exits
with 1 (use a case whose human acts from the start, 3-6, or more episodes).

``--learning NAME`` chooses the session's learning configuration (params/learning/; default
the sessions' default, ``sac``).

``--compare-learning`` (target: with learning inside episodes, the control period's p99 jitter
no worse than 1.2x without, measured in one run) runs the same session twice per round,
alternately: with the learning moved out of the episodes (SAC: ``sac_update_at=episode_end``,
the episode's gradient steps after its last state; PPO: ``horizon`` larger than an episode) and
with the configuration's learning inside them (SAC: its gradient steps at every step from the
first one, ``sac_learning_starts=1``, as in every episode after a session's first; PPO: an
update every ``--inside-horizon`` steps, run by the learner thread), and prints both and their
ratio::

    python bench/realtime_jitter.py --compare-learning --rounds 2

``--compare-foxglove`` (target: the Foxglove live view costs the control loop nothing
measurable) runs the same session alternately without and with ``hrc session --foxglove``, a
Foxglove WebSocket client connected and subscribed to every channel in the second arm (it
counts what it receives), and prints the jitter and latency of both and their ratio::

    python bench/realtime_jitter.py --compare-foxglove --rounds 2

``--realtime-priority N`` runs the session's nodes on SCHED_FIFO at priority N
(``HRC_REALTIME_PRIORITY``, hrc_common.realtime) and this listener's threads at the same priority,
so that its receive times are not delayed by ordinarily scheduled work either; 0 (default) = off.

Each run prints the settings it ran with (case, executor, human period, realtime priority, the
sets) and the machine's load and the CPU time the hypervisor took from this VM meanwhile
("steal", /proc/stat): on a shared virtual machine the largest delays come from there.
"""

import argparse
import asyncio
import os
import pathlib
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time

import rclpy
from geometry_msgs.msg import WrenchStamped
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor

from hrc_common import qos, topics
from hrc_common.executables import executable_path
from hrc_common.executors import EXECUTOR_VARIABLE
from hrc_common.paths import params_dir
from hrc_common.realtime import apply_realtime_priority, REALTIME_PRIORITY_VARIABLE
from hrc_common.session_plan import add_learning_option, load_learning
from hrc_msgs.msg import TaskState


def percentile(values, fraction):
    """Return the value at ``fraction`` (0..1) of the sorted values (nearest rank)."""
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(fraction * (len(ordered) - 1))))]


# Steal (% of CPU time) above which a run's p99 says more about the host than about the graph:
# on the 2-core development VM, runs at 1-4% steal gave period p99 3.3-7.8 ms, at 13-26% 24-60 ms.
STEAL_WARNING_PERCENT = 5.0


def cpu_ticks() -> tuple:
    """Return (steal, total) CPU ticks of the machine so far (/proc/stat; (0, 0) elsewhere)."""
    try:
        with open('/proc/stat') as stat:
            fields = [int(value) for value in stat.readline().split()[1:]]
    except (OSError, ValueError):
        return 0, 0
    return (fields[7] if len(fields) > 7 else 0), sum(fields[:8])


def machine_line(before: tuple, after: tuple) -> str:
    """Return the load and the hypervisor's steal share between two cpu_ticks() readings."""
    try:
        with open('/proc/loadavg') as loadavg:
            load = ' '.join(loadavg.read().split()[:3])
    except OSError:
        load = '?'
    total = after[1] - before[1]
    steal = 100.0 * (after[0] - before[0]) / total if total > 0 else 0.0
    line = f'load {load}, steal {steal:.1f}% of CPU time during the run'
    if steal > STEAL_WARNING_PERCENT:
        line += (f' (over {STEAL_WARNING_PERCENT:g}%: the hypervisor, not this graph, sets '
                 f'the p99 of this run)')
    return line


def free_port() -> int:
    """Return a TCP port that is free on the loopback now."""
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        return probe.getsockname()[1]


def measure(case: int, episodes: int, domain_id: int, settings=(), priority: int = 0,
            learning: str = 'sac', foxglove: bool = False) -> dict:
    """Run one realtime session; return its jitter and latency figures (ms), or {'error': ...}.

    ``priority`` > 0: the session's nodes and this listener on SCHED_FIFO at that priority.
    ``foxglove``: the session also serves the Foxglove live view, a viewer subscribed to all.
    """
    context = Context()
    rclpy.init(context=context, domain_id=domain_id)
    node = rclpy.create_node('bench_realtime', context=context)
    states = []       # (episode, step, stamp key, receive time)
    commands = {'robot': {}, 'human': {}}  # stamp key -> receive time

    def key(header):
        return (header.stamp.sec, header.stamp.nanosec)

    node.create_subscription(TaskState, topics.STATE, lambda m: states.append(
        (m.episode, m.step, key(m.header), time.perf_counter())), qos.STATE_QOS)
    for actor, topic in (('robot', topics.ROBOT_CMD_WRENCH), ('human', topics.HUMAN_CMD_WRENCH)):
        node.create_subscription(
            WrenchStamped, topic,
            lambda m, actor=actor: commands[actor].setdefault(key(m.header), time.perf_counter()),
            qos.COMMAND_QOS)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)

    def spin():
        try:
            while context.ok():
                executor.spin_once(timeout_sec=0.1)
        except ExternalShutdownException:
            pass

    thread = threading.Thread(target=spin, daemon=True)
    thread.start()
    environment = dict(os.environ)
    if priority > 0:
        environment[REALTIME_PRIORITY_VARIABLE] = str(priority)
        note = apply_realtime_priority(priority)
        if 'SCHED_FIFO priority' not in note:
            print(f'listener: {note}', file=sys.stderr)
    else:
        environment.pop(REALTIME_PRIORITY_VARIABLE, None)
    work = pathlib.Path(tempfile.mkdtemp(prefix='hrc-bench-rt-'))
    command = [str(executable_path('hrc_bringup', 'hrc')), 'session', '--case', str(case),
               '--mode', 'realtime', '--episodes', str(episodes), '--eval-episodes', '0',
               '--domain-id', str(domain_id), '--no-record', '--no-report',
               '--runs-dir', str(work / 'runs'), '--session-id', 'bench-realtime',
               '--learning', learning]
    for setting in settings:
        command += ['--set', setting]
    viewer_stop, viewer_frames = threading.Event(), []
    if foxglove:
        port = free_port()
        command += ['--foxglove', '--foxglove-port', str(port)]
        # the test support (test/support/hrc_testing) is not installed: found from the checkout
        sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'test' / 'support'))
        from hrc_testing.foxglove_client import follow   # lazy: only this arm needs a viewer
        viewer = threading.Thread(target=lambda: asyncio.run(follow(
            f'ws://127.0.0.1:{port}', lambda _topic, _message, size: viewer_frames.append(size),
            viewer_stop.is_set)), daemon=True)
        viewer.start()
    ticks_before = cpu_ticks()
    result = subprocess.run(command, capture_output=True, text=True, env=environment)
    ticks_after = cpu_ticks()
    viewer_stop.set()
    time.sleep(0.5)
    rclpy.shutdown(context=context)
    thread.join(timeout=5)
    if result.returncode != 0:
        return {'error': f'the session exited {result.returncode}:\n{result.stdout}'
                         f'{result.stderr}'}

    by_episode = {}
    for (episode, step, _, t), (next_episode, next_step, _, next_t) in zip(states, states[1:]):
        if next_episode == episode and next_step == step + 1:
            by_episode.setdefault(episode, []).append(next_t - t)
    realtime = {episode: values for episode, values in by_episode.items()
                if statistics.mean(values) > 0.1}
    figures = {'lockstep_episodes': sorted(set(by_episode) - set(realtime)),
               'machine': machine_line(ticks_before, ticks_after)}
    if foxglove:
        figures['viewer'] = (len(viewer_frames), sum(viewer_frames))
        if not viewer_frames:
            figures['error'] = 'the Foxglove viewer received nothing: the arm measured no view'
            return figures
    if not realtime:
        figures['error'] = ("no realtime episode to measure: in this case the first episodes "
                            "are the robot's alone, in lockstep; use --case 3..6 or more "
                            '--episodes')
        return figures
    intervals = [value for values in realtime.values() for value in values]
    realtime_stamps = {stamp for episode, _, stamp, _ in states if episode in realtime}
    jitter_ms = [abs(interval - 0.2) * 1000 for interval in intervals]
    figures.update(states=len(states), intervals=len(intervals),
                   mean_period_ms=statistics.mean(intervals) * 1000,
                   jitter_p50=percentile(jitter_ms, 0.5), jitter_p99=percentile(jitter_ms, 0.99),
                   jitter_max=max(jitter_ms))
    state_time = {stamp: t for _, _, stamp, t in states if stamp in realtime_stamps}
    for actor, received in commands.items():
        latency_ms = [(t - state_time[stamp]) * 1000 for stamp, t in received.items()
                      if stamp in state_time]
        if latency_ms:
            figures[actor] = (percentile(latency_ms, 0.5), percentile(latency_ms, 0.99),
                              len(latency_ms))
    return figures


def report(figures: dict, label: str = '') -> None:
    """Print one session's figures as the bench always has."""
    prefix = f'[{label}] ' if label else ''
    print(f'{prefix}{figures["machine"]}')
    if figures['lockstep_episodes']:
        print(f'{prefix}left out {len(figures["lockstep_episodes"])} episode(s) that ran in '
              f'lockstep (states faster than half the control period): '
              f'{figures["lockstep_episodes"]}')
    print(f'{prefix}states: {figures["states"]}, consecutive intervals: '
          f'{figures["intervals"]}, mean period {figures["mean_period_ms"]:.2f} ms')
    print(f'{prefix}period jitter |dt - 200 ms|: p50 {figures["jitter_p50"]:.2f} ms, '
          f'p99 {figures["jitter_p99"]:.2f} ms, max {figures["jitter_max"]:.2f} ms')
    if 'viewer' in figures:
        print(f'{prefix}the Foxglove viewer received {figures["viewer"][0]} messages '
              f'({figures["viewer"][1]} bytes)')
    for actor in ('robot', 'human'):
        if actor in figures:
            p50, p99, count = figures[actor]
            print(f'{prefix}{actor} command latency (state received -> command received): '
                  f'p50 {p50:.2f} ms, p99 {p99:.2f} ms ({count} commands)')


def comparison_arms(algorithm: str, inside_horizon: int) -> dict:
    """Return {label: agent settings} of --compare-learning's two arms for ``algorithm``."""
    if algorithm == 'sac':
        return {'learning between episodes': ['agent.sac_update_at=episode_end'],
                'learning inside episodes (every step)': ['agent.sac_learning_starts=1']}
    return {'learning between episodes': ['agent.horizon=1000000'],
            f'updates every {inside_horizon} steps': [f'agent.horizon={inside_horizon}']}


def settings_line(args) -> str:
    """Return the settings a run measures with, as one line."""
    human_period = next((setting.split('=', 1)[1] for setting in args.settings
                         if setting.startswith('sim.human_period=')), '0.02 (default)')
    priority = (f'SCHED_FIFO {args.realtime_priority}' if args.realtime_priority
                else 'off (ordinary scheduler)')
    return (f'settings: case {args.case}, {args.episodes} episode(s), learning '
            f'configuration {args.learning}, '
            f'{EXECUTOR_VARIABLE}={os.environ.get(EXECUTOR_VARIABLE, "lean")}, human_period '
            f'{human_period} s, realtime priority {priority}, sets: '
            f'{" ".join(args.settings) or "none"}')


def main() -> int:
    """Run the realtime session(s) and print the jitter and latency figures."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--case', type=int, default=4,
                        help='paper case (default 4: the human acts from the first episode, so '
                             'every episode is realtime)')
    parser.add_argument('--episodes', type=int, default=1)
    parser.add_argument('--domain-id', type=int, default=92)
    parser.add_argument('--set', dest='settings', action='append', default=[],
                        metavar='KEY=VALUE', help='a session setting (hrc session --set)')
    parser.add_argument('--realtime-priority', type=int, default=0, metavar='N',
                        help='run the nodes and this listener on SCHED_FIFO at priority N '
                             '(1..99; HRC_REALTIME_PRIORITY); default 0: off')
    add_learning_option(parser)
    parser.add_argument('--compare-learning', action='store_true',
                        help='run with the learning between and inside episodes, alternately')
    parser.add_argument('--compare-foxglove', action='store_true',
                        help='run without and with the Foxglove live view (a viewer '
                             'subscribed), alternately')
    parser.add_argument('--rounds', type=int, default=1,
                        help='rounds of the comparison (each: one session of each arm)')
    parser.add_argument('--inside-horizon', type=int, default=64,
                        help='PPO: steps between updates inside an episode in the learning '
                             'arm (default 64: 3 updates in a 200-step episode)')
    args = parser.parse_args()
    if args.episodes < 1 or args.rounds < 1 or args.inside_horizon < 2:
        parser.error('--episodes and --rounds must be >= 1, --inside-horizon >= 2')
    if not 0 <= args.realtime_priority <= 99:
        parser.error('--realtime-priority must be 0 (off) or 1..99')
    print(settings_line(args), flush=True)

    if args.compare_learning and args.compare_foxglove:
        parser.error('--compare-learning and --compare-foxglove: one comparison per run')
    if not (args.compare_learning or args.compare_foxglove):
        print(f'running a realtime session of {args.episodes} episode(s) of 40 s ...',
              flush=True)
        figures = measure(args.case, args.episodes, args.domain_id, args.settings,
                          args.realtime_priority, args.learning)
        if 'error' in figures:
            print(figures['error'], file=sys.stderr)
            return 1
        report(figures)
        return 0

    if args.compare_foxglove:
        arms = {'without the Foxglove view': (list(args.settings), False),
                'with the Foxglove view and a viewer': (list(args.settings), True)}
    else:
        try:
            algorithm = load_learning(params_dir(), args.learning)['algorithm']
        except (ValueError, KeyError) as error:
            parser.error(f'--learning {args.learning}: {error}')
        arms = {label: (list(args.settings) + settings, False)
                for label, settings in comparison_arms(algorithm, args.inside_horizon).items()}
    results = {label: [] for label in arms}
    for round_index in range(args.rounds):
        for label, (settings, foxglove) in arms.items():
            print(f'round {round_index + 1}/{args.rounds}: {label} '
                  f'({args.episodes} episode(s) of 40 s) ...', flush=True)
            figures = measure(args.case, args.episodes, args.domain_id, settings,
                              args.realtime_priority, args.learning, foxglove)
            if 'error' in figures:
                print(figures['error'], file=sys.stderr)
                return 1
            report(figures, label)
            results[label].append(figures)
    print('median over rounds:')
    p99 = {}
    for label, runs in results.items():
        p99[label] = statistics.median(run['jitter_p99'] for run in runs)
        latency = {actor: statistics.median(run[actor][1] for run in runs if actor in run)
                   for actor in ('robot', 'human') if any(actor in run for run in runs)}
        each = ', '.join(f'{run["jitter_p99"]:.2f}' for run in runs)
        print(f'  {label}: period jitter p99 {p99[label]:.2f} ms (rounds: {each}), command '
              f'latency p99 ' + ', '.join(f'{actor} {value:.2f} ms'
                                          for actor, value in latency.items()))
    (first, without), *others = p99.items()
    for label, value in others:
        print(f'jitter p99 {label} / {first}: {value / without:.2f}x')
    return 0


if __name__ == '__main__':
    sys.exit(main())
