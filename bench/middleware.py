#!/usr/bin/env python3
"""Benchmark: the lockstep graph against the middleware's limit, in one run.

    python bench/middleware.py                          # from any directory (~3-4 min)
    python bench/middleware.py --repeats 2 --executors lean rclpy

Prints, measured in the same run (so that the machine's load hits every figure alike):

1. ping-pong: round trip (ms) of a bare rclpy exchange between two processes, a TaskState out
   and a WrenchStamped back (what one lockstep exchange carries), for each executor named
   (``--executors``; both ends use the same one; 'rclpy' is the issue's "bare round trip");
2. engine: ms per control step of the in-process engine (``hrc_engine``, bags written) at each
   human rate (``--human-periods``, default 0.2 and 0.02 s);
3. graph: ms per control step of the ``session`` graph (sim, agent, human as processes over
   DDS) without and with the recorder, at each human rate, for each executor of the nodes
   (``HRC_EXECUTOR``, hrc_common.executors);
4. the share of the middleware's limit the graph reaches: graph step / (round trip x round
   trips per step + engine step), where a lockstep step takes 1 round trip with the human
   acting once a period and ``control_period / human_period`` round trips at the human's rate
   (one slice answer each; the robot's answer travels with the first). The round trip is the
   'rclpy' one when measured (the middleware with rclpy's executor), else the first executor's.
   The recorder's overhead on the rate and on the nodes' CPU (all the session's processes):
   over the whole session (start-up included: the recorder's own start, ~0.5 s of CPU, is most
   of it in a session of two episodes) and per step while the episodes ran (from the first state
   to the last, read from the threads' /proc schedstat; threads that end inside the window, an
   update's learner thread, are left out in both runs; also split by process, and what each
   process spends more with the recorder), and the recorder process's own CPU (its
   last log line), for each recorder variant named
   (``--recorders``: ``batched``, the default, drains its subscriptions every 0.05 s; the
   recorder with a callback per message is commit 8c1b998's ``per-message``).
5. with ``--compose sim,human ...``: the graph with those nodes in one process
   (``HRC_COMPOSE``, hrc_bringup.compose_nodes) against the same graph with a process per node:
   a composition with the recorder runs with the (batched) recorder and is compared with the
   separate graph with it, one without against the graph without a recorder; with both
   ``sim,human`` and ``sim,human,recorder``, the recorder's cost inside the composition.

Case 5 by default: the human acts from the start (case 2's first episodes are the robot's alone
and would hide the human's rate; ``--case 2 --human-periods 0.2`` measures them: the person's
wait in task first). Episodes run 200 steps; updates between episodes are left out
of the step times (steps are timed within episodes by a listener on /hrc/state).
"""

import argparse
import math
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile
import time

REPOSITORY = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPOSITORY / 'bench'))

PING = '/bench/ping'
PONG = '/bench/pong'
CONTROL_PERIOD_S = 0.2
# recorder variant -> its `hrc session --set` overrides
RECORDERS = {'batched': ()}


def echo(domain_id: int, executor_name: str) -> int:
    """Answer every TaskState on PING with a WrenchStamped carrying its stamp (child process)."""
    import rclpy  # lazy: rclpy only in the ping-pong processes
    from geometry_msgs.msg import WrenchStamped  # lazy: as rclpy above
    from hrc_common import qos  # lazy: as rclpy above
    from hrc_common.executors import make_executor  # lazy: as rclpy above
    from hrc_msgs.msg import TaskState  # lazy: as rclpy above

    rclpy.init(domain_id=domain_id)
    node = rclpy.create_node('bench_echo')
    publisher = node.create_publisher(WrenchStamped, PONG, qos.COMMAND_QOS,
                                      event_callbacks=qos.NO_PUBLISHER_EVENTS)

    def answer(state):
        reply = WrenchStamped()
        reply.header.stamp = state.header.stamp
        publisher.publish(reply)

    node.create_subscription(TaskState, PING, answer, qos.STATE_QOS,
                             event_callbacks=qos.NO_SUBSCRIPTION_EVENTS)
    executor = make_executor(executor_name)
    executor.add_node(node)
    try:
        executor.spin()
    except Exception:  # noqa: BLE001 - shut down from outside: the parent's SIGTERM
        pass
    return 0


def ping_pong(domain_id: int, executor_name: str, round_trips: int) -> float:
    """Return the median round trip (ms) of TaskState -> WrenchStamped with an echo process."""
    import rclpy  # lazy: rclpy only in the ping-pong processes
    from geometry_msgs.msg import WrenchStamped  # lazy: as rclpy above
    from hrc_common import qos  # lazy: as rclpy above
    from hrc_common.executors import make_executor  # lazy: as rclpy above
    from hrc_msgs.msg import TaskState  # lazy: as rclpy above
    from rclpy.context import Context  # lazy: as rclpy above

    environment = dict(os.environ, ROS_DOMAIN_ID=str(domain_id))
    child = subprocess.Popen([sys.executable, __file__, '--echo', str(domain_id),
                              executor_name], env=environment)
    context = Context()
    rclpy.init(context=context, domain_id=domain_id)
    try:
        node = rclpy.create_node('bench_ping', context=context)
        publisher = node.create_publisher(TaskState, PING, qos.STATE_QOS,
                                          event_callbacks=qos.NO_PUBLISHER_EVENTS)
        received = []
        subscription = node.create_subscription(
            WrenchStamped, PONG, lambda reply: received.append(reply), qos.COMMAND_QOS,
            event_callbacks=qos.NO_SUBSCRIPTION_EVENTS)
        executor = make_executor(executor_name, context=context)
        executor.add_node(node)
        deadline = time.monotonic() + 30
        while (publisher.get_subscription_count() == 0
               or subscription.get_publisher_count() == 0) and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        times = []
        state = TaskState(human_applied=[0.0] * 10)
        for index in range(round_trips + 100):   # the first 100: warm-up
            received.clear()
            state.header.stamp.nanosec = index
            start = time.perf_counter()
            publisher.publish(state)
            while not received:
                executor.spin_once(timeout_sec=1.0)
                if time.perf_counter() - start > 5:
                    raise RuntimeError('the echo process did not answer within 5 s')
            times.append(time.perf_counter() - start)
        executor.shutdown()
        node.destroy_node()
    finally:
        rclpy.shutdown(context=context)
        child.terminate()
        try:
            child.wait(timeout=10)
        except subprocess.TimeoutExpired:   # an executor that ignores SIGTERM (events)
            child.kill()
            child.wait()
    return statistics.median(times[100:]) * 1000


def recorder_cpu(work: pathlib.Path, session_id: str) -> float:
    """Return the recorder process's CPU (s) from its last log line (nan if not found)."""
    log = work / 'runs' / session_id / 'logs' / 'recorder.log'
    found = re.findall(r'process CPU ([0-9.]+) s', log.read_text() if log.is_file() else '')
    return float(found[-1]) if found else float('nan')


def graph_step(case, episodes, seed, recorder, domain_id, work, human_period, executor_name,
               compose=''):
    """Return graph_rate.graph_rate's result with the nodes on ``executor_name``.

    ``recorder``: None (no recorder) or a name of RECORDERS; then the result also holds the
    recorder process's CPU (``recorder_cpu``, s; nan when composed: its process is shared).
    ``compose``: HRC_COMPOSE of the session ('' = a process per node).
    """
    from graph_rate import graph_rate  # lazy: the sibling bench, found through sys.path above
    previous = os.environ.get('HRC_EXECUTOR')
    os.environ['HRC_EXECUTOR'] = executor_name
    os.environ['HRC_COMPOSE'] = compose
    try:
        result = graph_rate(case, episodes, seed, recorder is not None, domain_id, work,
                            human_period, RECORDERS.get(recorder, ()))
        if recorder is not None:
            result['recorder_cpu'] = recorder_cpu(work, result['session_id'])
        return result
    finally:
        del os.environ['HRC_COMPOSE']
        if previous is None:
            del os.environ['HRC_EXECUTOR']
        else:
            os.environ['HRC_EXECUTOR'] = previous


def running_cpu_costs(runs, baselines) -> list:
    """Return the sorted running CPU per step ratios - 1 of paired runs (both measured)."""
    return sorted(run['cpu_per_step'] / base['cpu_per_step'] - 1
                  for run, base in zip(runs, baselines)
                  if math.isfinite(run['cpu_per_step']) and math.isfinite(base['cpu_per_step'])
                  and base['cpu_per_step'] > 0)


def by_process(result: dict) -> str:
    """Return a graph run's running CPU per step by process ('sim_node 0.812, ...', ms)."""
    return ', '.join(f'{label} {seconds * 1000:.3f}' for label, seconds
                     in sorted(result['cpu_per_step_by_process'].items())) or 'n/a'


def main() -> int:
    """Measure everything in rounds and print the figures and ratios."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--case', type=int, default=5)
    parser.add_argument('--episodes', type=int, default=2, help='episodes per graph run')
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--domain-id', type=int, default=92)
    parser.add_argument('--repeats', type=int, default=1, help='rounds of every measurement')
    parser.add_argument('--round-trips', type=int, default=2000)
    parser.add_argument('--human-periods', type=float, nargs='+', default=[0.2, 0.02])
    parser.add_argument('--executors', nargs='+', default=['lean', 'rclpy'],
                        choices=('lean', 'rclpy'),
                        help='executors of the nodes and of the ping-pong (HRC_EXECUTOR)')
    parser.add_argument('--graph-executors', nargs='+', default=None,
                        choices=('lean', 'rclpy'),
                        help='executors of the graph runs (default: --executors)')
    parser.add_argument('--recorders', nargs='+', default=['batched'],
                        choices=tuple(RECORDERS),
                        help='recorder variants measured against the graph without one')
    parser.add_argument('--compose', nargs='*', default=[], metavar='NODES',
                        help='compositions (HRC_COMPOSE, e.g. sim,human) measured against a '
                             'process per node')
    parser.add_argument('--echo', nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.echo:
        return echo(int(args.echo[0]), args.echo[1])
    from graph_rate import engine_rate  # lazy: the sibling bench, found through sys.path above
    graph_executors = args.graph_executors or args.executors

    print(f'machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}; case {args.case}, '
          f'{args.episodes} episodes of 200 steps per run, {args.repeats} round(s)', flush=True)
    rounds = []
    with tempfile.TemporaryDirectory(prefix='hrc-bench-') as folder:
        work = pathlib.Path(folder)
        for index in range(args.repeats):
            figures = {'rt': {}, 'engine': {}, 'graph': {}}
            for name in args.executors:
                figures['rt'][name] = ping_pong(args.domain_id, name, args.round_trips)
                print(f'round {index + 1}: ping-pong ({name} executor): round trip '
                      f'{figures["rt"][name]:.3f} ms', flush=True)
            for period in args.human_periods:
                rate = engine_rate(args.case, args.episodes, args.seed, work, period)
                figures['engine'][period] = 1000 / rate
                print(f'round {index + 1}: engine, human_period {period:g} s: '
                      f'{1000 / rate:.3f} ms/step ({rate:.0f} steps/s)', flush=True)
                for name in graph_executors:
                    # the variants in a rotated order each round: at human_period 0.2 s the
                    # second graph run of a round was slower than the third in 7 of 8 rounds
                    # (by 10-77%), whichever recorder it ran (cause not found)
                    variants = ([(None, '')] + [(recorder, '') for recorder in args.recorders]
                                + [('batched' if 'recorder' in compose.split(',') else None,
                                    compose) for compose in args.compose])
                    shift = index % len(variants)
                    for recorder, compose in variants[shift:] + variants[:shift]:
                        result = graph_step(args.case, args.episodes, args.seed, recorder,
                                            args.domain_id, work, period, name, compose)
                        figures['graph'][(period, name, compose or recorder)] = result
                        if compose:
                            what = f', composed {compose}'
                        else:
                            what = f', recorder {recorder}' if recorder else ''
                        own = (f', recorder process {result["recorder_cpu"]:.2f} s'
                               if recorder and not compose else '')
                        print(f'round {index + 1}: graph ({name}), human_period {period:g} s'
                              f'{what}: {1000 / result["rate"]:.3f} ms/step '
                              f'({result["rate"]:.0f} steps/s, nodes CPU {result["cpu"]:.1f} s'
                              f'{own} in {result["wall"]:.1f} s; while the episodes ran '
                              f'{result["cpu_per_step"] * 1000:.3f} ms CPU/step: '
                              f'{by_process(result)})', flush=True)
            rounds.append(figures)
    median = statistics.median
    reference = 'rclpy' if 'rclpy' in args.executors else args.executors[0]
    print(f'-- summary (median of {len(rounds)} round(s); limit = {reference} round trip x '
          f'round trips per step + engine step)')
    for name in args.executors:
        print(f'ping-pong round trip, {name:5s} executor     : '
              f'{median(r["rt"][name] for r in rounds):7.3f} ms')
    for period in args.human_periods:
        trips = max(1, round(CONTROL_PERIOD_S / period))
        engine = median(r['engine'][period] for r in rounds)
        limit = median(r['rt'][reference] * trips + r['engine'][period] for r in rounds)
        print(f'human_period {period:g} s ({trips} round trip(s) per step): engine '
              f'{engine:.3f} ms/step, limit {limit:.3f} ms/step')
        for name in graph_executors:
            plain = [r['graph'][(period, name, None)] for r in rounds]
            step = median(1000 / g['rate'] for g in plain)
            ratio = median(1000 / r['graph'][(period, name, None)]['rate']
                           / (r['rt'][reference] * trips + r['engine'][period]) for r in rounds)
            print(f'  graph ({name:5s}): {step:7.3f} ms/step; graph / limit {ratio:.2f}')
            for recorder in args.recorders:
                recorded = [r['graph'][(period, name, recorder)] for r in rounds]
                step_recorded = median(1000 / g['rate'] for g in recorded)
                rate_cost = median(1 - g['rate'] / p['rate'] for g, p in zip(recorded, plain))
                rate_costs = sorted(1 - g['rate'] / p['rate'] for g, p in zip(recorded, plain))
                cpu_cost = median(g['cpu'] / p['cpu'] - 1 for g, p in zip(recorded, plain))
                cpu_costs = sorted(g['cpu'] / p['cpu'] - 1 for g, p in zip(recorded, plain))
                # rounds where both runs gave a running CPU (nan: no state, or none at an
                # episode's end, was heard)
                running_costs = running_cpu_costs(recorded, plain)
                own = median(g['recorder_cpu'] for g in recorded)
                print(f'    with recorder {recorder:11s}: {step_recorded:7.3f} ms/step; costs '
                      f'{rate_cost * 100:+.1f}% of the rate (rounds {rate_costs[0] * 100:+.1f}'
                      f'..{rate_costs[-1] * 100:+.1f}), {cpu_cost * 100:+.1f}% nodes CPU '
                      f'({cpu_costs[0] * 100:+.1f}..{cpu_costs[-1] * 100:+.1f}); recorder '
                      f'process {own:.2f} s CPU')
                running = (f'{median(running_costs) * 100:+.1f}% (rounds '
                           f'{running_costs[0] * 100:+.1f}..{running_costs[-1] * 100:+.1f})'
                           if running_costs else 'n/a (no round measured it)')
                print(f'      session CPU per step while the episodes ran (start-up and '
                      f'shutdown left out): {running}')
                # where that goes: the recorder process's own and what the others add (their
                # deliveries to one more reader), medians of the rounds, ms per step
                labels = sorted({label for g in recorded + plain
                                 for label in g['cpu_per_step_by_process']})
                shares = []
                for label in labels:
                    added = [g['cpu_per_step_by_process'].get(label, 0.0)
                             - p['cpu_per_step_by_process'].get(label, 0.0)
                             for g, p in zip(recorded, plain)
                             if g['cpu_per_step_by_process'] and p['cpu_per_step_by_process']]
                    if added:
                        shares.append(f'{label} {median(added) * 1000:+.3f}')
                if shares:
                    print(f'      by process, ms CPU per step with the recorder minus without: '
                          f'{", ".join(shares)}')
            for compose in args.compose:
                separate = 'batched' if 'recorder' in compose.split(',') else None
                if (period, name, separate) not in rounds[0]['graph']:
                    print(f'    composed {compose}: (no separate graph with recorder '
                          f'{separate} measured: add --recorders {separate})')
                    continue
                composed = [r['graph'][(period, name, compose)] for r in rounds]
                apart = [r['graph'][(period, name, separate)] for r in rounds]
                ratios = sorted(p['rate'] / c['rate'] for c, p in zip(composed, apart))
                cpu = median(c['cpu'] / p['cpu'] for c, p in zip(composed, apart))
                composed_step = median(1000 / c['rate'] for c in composed)
                print(f'    composed {compose:19s}: {composed_step:7.3f} ms/step; step time '
                      f'composed / a process per node {median(ratios):.2f} (rounds '
                      f'{ratios[0]:.2f}..{ratios[-1]:.2f}), nodes CPU x{cpu:.2f}')
                without = ','.join(n for n in compose.split(',') if n != 'recorder')
                if without != compose and (period, name, without) in rounds[0]['graph']:
                    # the recorder's cost inside a composition: against the same composition
                    # without it, in the same rounds
                    bare = [r['graph'][(period, name, without)] for r in rounds]
                    rate_costs = sorted(1 - c['rate'] / b['rate'] for c, b in zip(composed, bare))
                    cpu_costs = running_cpu_costs(composed, bare)
                    cpu_text = (f'{median(cpu_costs) * 100:+.1f}% (rounds '
                                f'{cpu_costs[0] * 100:+.1f}..{cpu_costs[-1] * 100:+.1f})'
                                if cpu_costs else 'n/a')
                    print(f'      the recorder composed with {without} (against {without} '
                          f'composed without it): costs {median(rate_costs) * 100:+.1f}% of '
                          f'the rate (rounds {rate_costs[0] * 100:+.1f}..'
                          f'{rate_costs[-1] * 100:+.1f}), session CPU per step while the '
                          f'episodes ran {cpu_text}')
    print(f'load average at the end: {os.getloadavg()[0]:.1f}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
