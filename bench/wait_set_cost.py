#!/usr/bin/env python3
"""Benchmark: what each entity in a node's wait set costs rclpy's executor per turn.

    python bench/wait_set_cost.py            # from any directory, no other node needed

rclpy's SingleThreadedExecutor rebuilds its wait set in Python at every turn, so every entity
of a node (subscription, publisher event handler, timer, service, parameter services) costs
time at every message of the control loop. This measures turns per second of a node whose
only work is a timer that is always due, with extra entities of one kind added, and prints
the cost of one entity of each kind (us per turn) from one run. (The lockstep graph takes a
few turns per control step in each node.)
"""

import statistics
import sys
import time

import rclpy
from geometry_msgs.msg import WrenchStamped
from rclpy.context import Context
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.executors import SingleThreadedExecutor
from std_srvs.srv import Trigger

TURNS = 3000
EXTRA = 20


def turns_per_second(build) -> float:
    """Return executor turns/s of a node with an always-due timer plus ``build(node)``."""
    context = Context()
    rclpy.init(context=context, domain_id=99)
    try:
        node = rclpy.create_node('wait_set_bench', context=context,
                                 start_parameter_services=getattr(build, 'parameters', False))
        node.create_timer(0.0, lambda: None)
        build(node)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        for _ in range(200):
            executor.spin_once(timeout_sec=1.0)
        started = time.perf_counter()
        for _ in range(TURNS):
            executor.spin_once(timeout_sec=1.0)
        rate = TURNS / (time.perf_counter() - started)
        executor.shutdown()
        node.destroy_node()
        return rate
    finally:
        rclpy.shutdown(context=context)


def main() -> int:
    """Measure each kind of entity and print its cost per turn."""
    quiet_pub = PublisherEventCallbacks(use_default_callbacks=False)
    quiet_sub = SubscriptionEventCallbacks(use_default_callbacks=False)

    def publishers(default_events):
        def build(node):
            for index in range(EXTRA):
                node.create_publisher(WrenchStamped, f'/bench/p{index}', 1,
                                      event_callbacks=None if default_events else quiet_pub)
        return build

    def subscriptions(default_events):
        def build(node):
            for index in range(EXTRA):
                node.create_subscription(WrenchStamped, f'/bench/s{index}', lambda m: None, 1,
                                         event_callbacks=None if default_events else quiet_sub)
        return build

    def timers(node):
        for _ in range(EXTRA):
            node.create_timer(100.0, lambda: None)

    def services(node):
        for index in range(EXTRA):
            node.create_service(Trigger, f'/bench/srv{index}', lambda request, response: response)

    def nothing(node):
        pass

    def parameter_services(node):
        pass
    parameter_services.parameters = True

    kinds = [('publisher (default QoS event handlers)', publishers(True), EXTRA),
             ('publisher (no event handlers)', publishers(False), EXTRA),
             ('subscription (default event handlers)', subscriptions(True), EXTRA),
             ('subscription (no event handlers)', subscriptions(False), EXTRA),
             ('timer (not due)', timers, EXTRA),
             ('service', services, EXTRA),
             ('parameter services (the 6 of a node, as a set)', parameter_services, 1)]
    rounds = 3
    base_rates, rates = [], {name: [] for name, _, _ in kinds}
    for _ in range(rounds):
        base_rates.append(turns_per_second(nothing))
        for name, build, _ in kinds:
            rates[name].append(turns_per_second(build))
    base = statistics.median(base_rates)
    print(f'executor turns/s with one always-due timer: {base:.0f} ({1e6 / base:.0f} us/turn); '
          f'medians of {rounds} rounds')
    for name, _, count in kinds:
        rate = statistics.median(rates[name])
        cost = (1e6 / rate - 1e6 / base) / count
        print(f'  + {count:2d} x {name:48s}: {rate:6.0f} turns/s -> {cost:6.1f} us per turn '
              f'each')
    return 0


if __name__ == '__main__':
    sys.exit(main())
