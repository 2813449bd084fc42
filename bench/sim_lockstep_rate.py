#!/usr/bin/env python3
"""Measure how many lockstep control steps per second the sim node makes over DDS.

Starts ``sim_node`` (lockstep, expected actors robot and human) in a subprocess on a private
domain; this process answers every state with a robot and a human command carrying the state's
stamp (zero wrench), from one rclpy node, and counts the states over whole episodes. Then it
steps the pure physics core in-process for the same number of steps and prints both rates and
their ratio. Not a test: numbers depend on the machine.

    source scripts/env.sh && python bench/sim_lockstep_rate.py [--episodes 5]
"""

import argparse
import os
import pathlib
import random
import sys
import time

import rclpy
from geometry_msgs.msg import WrenchStamped
from hrc_common import qos, topics
from hrc_msgs.msg import TaskState
from hrc_msgs.srv import ResetEpisode
from hrc_sim_node.physics import SliderPendulumBall
from rclpy.executors import SingleThreadedExecutor
from rclpy.experimental import EventsExecutor

# The test support (test/support/hrc_testing) is not installed: found from the checkout.
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'test' / 'support'))
from hrc_testing.nodes import NodeProcess, ros_environment  # noqa: E402 (after the path)


def in_process_rate(steps: int) -> float:
    """Control steps per second of the physics core alone (zero commands, whole episodes)."""
    physics = SliderPendulumBall()
    done = 0
    start = time.perf_counter()
    while done < steps:
        state = physics.reset(seed=done)
        while not state.truncated and done < steps:
            state = physics.step(0.0, 0.0)
            done += 1
    elapsed = time.perf_counter() - start
    physics.close()
    return done / elapsed


def lockstep_rate(episodes: int, executor_name: str) -> tuple:
    """Return (control steps/s, steps, missing flags seen) of the sim node over DDS."""
    domain_id = random.randint(101, 200)
    env = ros_environment(domain_id)
    os.environ.update({k: v for k, v in env.items() if k.startswith('ROS_')})
    sim = NodeProcess('hrc_sim_node', 'sim_node', env=env, parameters={
        'mode': 'lockstep', 'auto_reset': True, 'marker_rate': 0.0, 'lockstep_timeout': 5.0,
        'max_episodes': episodes + 1})
    rclpy.init(domain_id=domain_id)
    node = rclpy.create_node('bench_commands')
    robot = node.create_publisher(WrenchStamped, topics.ROBOT_CMD_WRENCH, qos.COMMAND_QOS)
    human = node.create_publisher(WrenchStamped, topics.HUMAN_CMD_WRENCH, qos.COMMAND_QOS)
    counts = {'states': 0, 'missing': 0, 'episodes': 0, 'start': None, 'end': None}

    def on_state(state):
        counts['missing'] += state.robot_command_missing + state.human_command_missing
        if state.truncated or state.terminated:
            if counts['start'] is None:  # episode 0 warms up (discovery); time whole episodes
                counts['start'] = time.perf_counter()
            else:
                counts['episodes'] += 1
                if counts['episodes'] == episodes:
                    counts['end'] = time.perf_counter()
            return
        if counts['start'] is not None and counts['end'] is None:
            counts['states'] += 1
        command = WrenchStamped()
        command.header.stamp = state.header.stamp
        command.header.frame_id = 'world'
        robot.publish(command)
        human.publish(command)

    node.create_subscription(TaskState, topics.STATE, on_state, qos.STATE_QOS)
    client = node.create_client(ResetEpisode, topics.RESET_SERVICE)
    if executor_name == 'events':
        executor = EventsExecutor()
    else:
        executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        deadline = time.monotonic() + 30
        while not client.service_is_ready() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)
        # Wait until the sim's subscriptions see our publishers, then start episode 0.
        while (robot.get_subscription_count() == 0 or human.get_subscription_count() == 0) \
                and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)
        future = client.call_async(ResetEpisode.Request(seed=1, episode=0))
        deadline = time.monotonic() + 60 + 10 * episodes
        while counts['end'] is None and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)
        del future
    finally:
        node.destroy_node()
        rclpy.shutdown()
        sim.stop()
    if counts['end'] is None:
        print(sim.output, file=sys.stderr)
        raise SystemExit('the sim did not finish the episodes in time')
    # Each episode: 200 answered states + the final one; count control steps (200 per episode).
    elapsed = counts['end'] - counts['start']
    return counts['states'] / elapsed, counts['states'], counts['missing']


def main() -> int:
    """Print the lockstep rate over DDS, the in-process rate, and their ratio."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--episodes', type=int, default=5, help='episodes timed (200 steps)')
    parser.add_argument('--executor', choices=('single', 'events'), default='single',
                        help='executor of this command publisher')
    arguments = parser.parse_args()
    rate, steps, missing = lockstep_rate(arguments.episodes, arguments.executor)
    physics_rate = in_process_rate(steps)
    print(f'lockstep over DDS : {rate:8.0f} control steps/s ({steps} steps, '
          f'{missing} missing-command flags)')
    print(f'physics in-process: {physics_rate:8.0f} control steps/s')
    print(f'ratio             : {physics_rate / rate:8.1f}x (in-process / lockstep)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
