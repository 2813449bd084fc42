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

``--gamepad``: the stick is a gamepad on the person's page instead (the browser's Gamepad API,
a virtual gamepad in headless Chromium in place of ``navigator.getGamepads``): the page sends
it every 20 ms to the display node, which publishes ``/joy``, which the human node reads
(``input: joy``). A move's time is taken just before the call that sets the virtual stick, so
the latency includes the page's sampling (every 5 ms) and the WebDriver call (a few ms)::

    python bench/stick_latency.py --gamepad --moves 300
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
# N*m: a move is found by its value; /joy carries float32 (a gamepad's moves differ by 1e-3)
VALUE_TOLERANCE = 1e-6


def percentile(values, fraction):
    """Return the value at ``fraction`` (0..1) of the sorted values (nearest rank)."""
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(fraction * (len(ordered) - 1))))]


def raw_of(index: int) -> int:
    """Return a unique raw axis value for move ``index`` (alternating sign, growing)."""
    magnitude = 2000 + 97 * index
    return magnitude if index % 2 else -magnitude


class FifoStick:
    """A joystick device: js_event records written to a FIFO the human node reads."""

    def __init__(self, work: pathlib.Path):
        self.fifo = work / 'js0'
        os.mkfifo(self.fifo)
        self.human_parameters = {'input': 'device', 'device': str(self.fifo), 'axis': AXIS}
        self.descriptor = None

    def start(self) -> None:
        self.descriptor = os.open(self.fifo, os.O_WRONLY)   # the human node holds the other end
        self.started = time.monotonic()
        time.sleep(1.0)                                     # let it see the device open

    def move(self, index: int) -> tuple:
        """Move the stick; return (write time, the command the sim applies, N*m)."""
        raw = raw_of(index)
        os.write(self.descriptor, pack_event(
            int((time.monotonic() - self.started) * 1000) & 0xFFFFFFFF, raw, JS_EVENT_AXIS, AXIS))
        return time.perf_counter(), device_axis(raw) * MAX_TORQUE

    def stop(self) -> None:
        os.close(self.descriptor)


class PageGamepad:
    """A virtual gamepad on the person's page in headless Chromium (``--gamepad``)."""

    def __init__(self, env: dict):
        self.display = NodeProcess('hrc_live', 'display_node', env=env,
                                   parameters={'port': 0, 'gamepad': True})
        self.human_parameters = {'input': 'joy', 'axis': 0}

    def start(self) -> None:
        sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'src' / 'hrc_live'
                               / 'test'))
        from browser import open_browser   # lazy: only --gamepad needs Chromium
        from page_graph import served_port  # lazy: the page tests' helpers, with Chromium
        self.browser = open_browser(1280, 720)
        self.browser.get(f'http://127.0.0.1:{served_port(self.display)}/')
        self.browser.execute_script(
            "window.virtualPad = {index: 0, id: 'bench gamepad', connected: true, mapping: "
            "'standard', axes: [0, 0.9, 0, 0], buttons: [{pressed: false}]}; "
            'navigator.getGamepads = () => [window.virtualPad];')   # 0.9: the stick chosen
        time.sleep(1.0)

    def move(self, index: int) -> tuple:
        """Move the stick; return (time before the call, the command the sim applies, N*m)."""
        value = (0.2 + 0.002 * index) * (1 if index % 2 else -1)   # unique, inside [-1, 1]
        written = time.perf_counter()
        self.browser.execute_script(f'window.virtualPad.axes[1] = {value}')
        return written, -value * MAX_TORQUE                          # /joy: stick up is +

    def stop(self) -> None:
        self.browser.quit()
        self.display.stop()


def measure(name: str, human_period: float, args, domain_id: int) -> dict:
    """Run at ``human_period`` (s); return the latencies (ms) and the count of lost moves."""
    work = pathlib.Path(tempfile.mkdtemp(prefix='hrc-stick-'))
    env = ros_environment(domain_id)
    stick = PageGamepad(env) if args.gamepad else FifoStick(work)
    sim = NodeProcess('hrc_sim_node', 'sim_node', env=env, parameters={
        'mode': 'realtime', 'start_on_launch': True, 'auto_reset': True,
        'expected_actors': ['human'], 'robot_dof': 'translation', 'marker_rate': 0.0,
        'human_period': human_period})
    human = NodeProcess('hrc_joystick_node', 'human_node', env=env, parameters={
        **stick.human_parameters, 'deadzone': 0.0, 'on_input_lost': 'zero', 'dof': 'rotation',
        'input_check_period': 0.1})
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
        stick.start()
        for index in range(args.moves):
            writes.append(stick.move(index))
            time.sleep(args.interval)
        time.sleep(0.6)
    finally:
        stick.stop()
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
        first = next((at for at, got in applied
                      if at >= written and abs(got - value) < VALUE_TOLERANCE), None)
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
    parser.add_argument('--gamepad', action='store_true',
                        help="a gamepad on the person's page (headless Chromium) instead of a "
                             'joystick device')
    args = parser.parse_args()
    for offset, human_period in enumerate(args.human_period):
        name = (f'human_period {human_period} s, '
                f'{"gamepad through the page" if args.gamepad else "stick forwarded"}')
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
