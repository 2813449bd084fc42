#!/usr/bin/env python3
"""Benchmark: realtime stick-to-physics latency, a scripted joystick on a FIFO.

    python bench/stick_latency.py                 # the sim's default human period (0.02 s)
    python bench/stick_latency.py --moves 300 --human-period 0.02 0.2

Starts a realtime sim (``start_on_launch``, the human alone: ``expected_actors [human]``) and a
human node reading a joystick device, a FIFO written by this process (Linux js_event records).
This process moves the stick to a new, unique position every ``--interval`` s (not a multiple
of the sim's periods, so the moves fall anywhere in a period) and listens on ``/hrc/state``
and ``/hrc/sim/slice_state``. The period's state carries ``human_applied``, the human command
the sim applied in each slice; a slice was applied at the tick that published the next slice
state (or the next period's state). Latency of a move = that tick's receive time minus the
time the event was written, both taken in this process. Moves overwritten before any tick
applied them are counted as never applied.

The human node sends each move at once (answering the newest state) and the sim applies the
newest command at each slice of ``--human-period`` s (default 0.02 s, the sim's; several values
run one after the other in one invocation).
"""

import argparse
import os
import pathlib
import statistics
import sys
import tempfile
import threading
import time

import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor

from hrc_common import qos, topics
from hrc_joystick_node.js_event import device_axis, JS_EVENT_AXIS, pack_event
from hrc_msgs.msg import TaskState

# The test support (test/support/hrc_testing) is not installed: found from the checkout.
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'test' / 'support'))
from hrc_testing.nodes import NodeProcess, ros_environment  # noqa: E402 (after the path)

AXIS = 1
MAX_TORQUE = 0.5      # N*m: the sim's default, the human drives the rotation here


def percentile(values, fraction):
    """Return the value at ``fraction`` (0..1) of the sorted values (nearest rank)."""
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(fraction * (len(ordered) - 1))))]


def raw_of(index: int) -> int:
    """Return a unique raw axis value for move ``index`` (alternating sign, growing)."""
    magnitude = 2000 + 97 * index
    return magnitude if index % 2 else -magnitude


def measure(name: str, human_period: float, args, domain_id: int) -> dict:
    """Run at ``human_period`` (s); return the latencies (ms) and the count of lost moves."""
    work = pathlib.Path(tempfile.mkdtemp(prefix='hrc-stick-'))
    fifo = work / 'js0'
    os.mkfifo(fifo)
    env = ros_environment(domain_id)
    sim = NodeProcess('hrc_sim_node', 'sim_node', env=env, parameters={
        'mode': 'realtime', 'start_on_launch': True, 'auto_reset': True,
        'expected_actors': ['human'], 'robot_dof': 'translation', 'marker_rate': 0.0,
        'human_period': human_period})
    human = NodeProcess('hrc_joystick_node', 'human_node', env=env, parameters={
        'input': 'device', 'device': str(fifo), 'axis': AXIS, 'deadzone': 0.0,
        'on_input_lost': 'zero', 'dof': 'rotation', 'input_check_period': 0.1})
    context = Context()
    rclpy.init(context=context, domain_id=domain_id)
    node = rclpy.create_node('bench_stick_latency', context=context)
    periods = []      # (episode, step, human_applied, receive time)
    slices = {}       # (episode, step, slice) -> receive time
    node.create_subscription(TaskState, topics.STATE, lambda m: periods.append(
        (m.episode, m.step, list(m.human_applied), time.perf_counter())), qos.STATE_QOS)
    node.create_subscription(TaskState, topics.SLICE_STATE, lambda m: slices.setdefault(
        (m.episode, m.step, m.slice), time.perf_counter()), qos.STATE_QOS)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)

    def spin():
        try:
            while context.ok():
                executor.spin_once(timeout_sec=0.05)
        except ExternalShutdownException:
            pass

    thread = threading.Thread(target=spin, daemon=True)
    thread.start()
    writes = []
    try:
        deadline = time.monotonic() + 60
        while len(periods) < 5 and time.monotonic() < deadline:
            time.sleep(0.05)
        if len(periods) < 5:
            raise RuntimeError(f'{name}: the realtime sim published no states\n{sim.output}')
        descriptor = os.open(fifo, os.O_WRONLY)   # the human node holds the reading end
        time.sleep(1.0)                           # let it see the device open
        started = time.monotonic()
        for index in range(args.moves):
            raw = raw_of(index)
            os.write(descriptor, pack_event(int((time.monotonic() - started) * 1000) & 0xFFFFFFFF,
                                            raw, JS_EVENT_AXIS, AXIS))
            writes.append((time.perf_counter(), device_axis(raw) * MAX_TORQUE))
            time.sleep(args.interval)
        time.sleep(0.6)
        os.close(descriptor)
    finally:
        rclpy.shutdown(context=context)
        thread.join(timeout=5)
        human.stop()
        sim.stop()

    # When each slice of each period was applied: the next slice state's (or state's) time.
    applied = []      # (apply time, value)
    for (episode, step, values, received) in periods:
        if step == 0 or not values:
            continue
        count = len(values)
        for index, value in enumerate(values):
            if index + 1 < count:
                at = slices.get((episode, step - 1, index + 1))
            else:
                at = received
            if at is not None:
                applied.append((at, value))
    applied.sort()
    latencies, lost = [], 0
    for written, value in writes:
        first = next((at for at, got in applied if at >= written and abs(got - value) < 1e-9),
                     None)
        if first is None:
            lost += 1
        else:
            latencies.append((first - written) * 1000)
    return {'latencies': latencies, 'lost': lost, 'moves': len(writes)}


def main() -> int:
    """Run each human period and print p50/p99 stick-to-physics latency."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--moves', type=int, default=150, help='stick moves per human period')
    parser.add_argument('--human-period', type=float, nargs='+', default=[0.02],
                        help="the sim's human_period (s) to run at (default 0.02)")
    parser.add_argument('--interval', type=float, default=0.037,
                        help='wall seconds between two moves (default 37 ms)')
    parser.add_argument('--domain-id', type=int, default=93)
    args = parser.parse_args()
    for offset, human_period in enumerate(args.human_period):
        name = f'human_period {human_period} s, stick forwarded'
        result = measure(name, human_period, args, args.domain_id + offset)
        latencies = result['latencies']
        if not latencies:
            print(f'{name}: no move was applied ({result["moves"]} written)')
            continue
        print(f'{name}: stick-to-physics latency p50 {percentile(latencies, 0.5):.1f} ms, '
              f'p99 {percentile(latencies, 0.99):.1f} ms, max {max(latencies):.1f} ms, '
              f'mean {statistics.mean(latencies):.1f} ms; {len(latencies)} of '
              f'{result["moves"]} moves applied, {result["lost"]} overwritten before a tick',
              flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
