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
"""

import argparse
import pathlib
import statistics
import subprocess
import sys
import tempfile
import threading
import time


def percentile(values, fraction):
    """Return the value at ``fraction`` (0..1) of the sorted values (nearest rank)."""
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(fraction * (len(ordered) - 1))))]


def main() -> int:
    """Run the realtime session and print the jitter and latency figures."""
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor

    from geometry_msgs.msg import WrenchStamped
    from hrc_common import qos, topics
    from hrc_common.testing import executable_path
    from hrc_msgs.msg import TaskState

    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--case', type=int, default=4,
                        help='paper case (default 4: the human acts from the first episode, so '
                             'every episode is realtime)')
    parser.add_argument('--episodes', type=int, default=1)
    parser.add_argument('--domain-id', type=int, default=92)
    args = parser.parse_args()

    context = Context()
    rclpy.init(context=context, domain_id=args.domain_id)
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
    work = pathlib.Path(tempfile.mkdtemp(prefix='hrc-bench-rt-'))
    command = [str(executable_path('hrc_bringup', 'hrc')), 'session', '--case', str(args.case),
               '--mode', 'realtime', '--episodes', str(args.episodes), '--eval-episodes', '0',
               '--domain-id', str(args.domain_id), '--no-record', '--no-report',
               '--runs-dir', str(work / 'runs'), '--session-id', 'bench-realtime']
    print(f'running a realtime session of {args.episodes} episode(s) of 40 s ...', flush=True)
    result = subprocess.run(command, capture_output=True, text=True)
    time.sleep(0.5)
    rclpy.shutdown(context=context)
    thread.join(timeout=5)
    if result.returncode != 0:
        print(result.stdout, result.stderr, file=sys.stderr)
        return 1

    by_episode = {}
    for (episode, step, _, t), (next_episode, next_step, _, next_t) in zip(states, states[1:]):
        if next_episode == episode and next_step == step + 1:
            by_episode.setdefault(episode, []).append(next_t - t)
    realtime = {episode: values for episode, values in by_episode.items()
                if statistics.mean(values) > 0.1}
    lockstep = sorted(set(by_episode) - set(realtime))
    if lockstep:
        print(f'left out {len(lockstep)} episode(s) that ran in lockstep (states faster than '
              f'half the control period): {lockstep}')
    if not realtime:
        print('no realtime episode to measure: in this case the first episodes are the '
              "robot's alone, in lockstep; use --case 3..6 or more --episodes", file=sys.stderr)
        return 1
    intervals = [value for values in realtime.values() for value in values]
    realtime_stamps = {stamp for episode, _, stamp, _ in states if episode in realtime}
    jitter_ms = [abs(interval - 0.2) * 1000 for interval in intervals]
    print(f'states: {len(states)}, consecutive intervals: {len(intervals)}, '
          f'mean period {statistics.mean(intervals) * 1000:.2f} ms')
    print(f'period jitter |dt - 200 ms|: p50 {percentile(jitter_ms, 0.5):.2f} ms, '
          f'p99 {percentile(jitter_ms, 0.99):.2f} ms, max {max(jitter_ms):.2f} ms')
    state_time = {stamp: t for _, _, stamp, t in states if stamp in realtime_stamps}
    for actor, received in commands.items():
        latency_ms = [(t - state_time[stamp]) * 1000 for stamp, t in received.items()
                      if stamp in state_time]
        if latency_ms:
            print(f'{actor} command latency (state received -> command received): '
                  f'p50 {percentile(latency_ms, 0.5):.2f} ms, p99 '
                  f'{percentile(latency_ms, 0.99):.2f} ms ({len(latency_ms)} commands)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
