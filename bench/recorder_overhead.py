#!/usr/bin/env python3
"""Benchmark the recorder: bytes per episode, recorder CPU, lockstep steps/s with and without it.

The graph is emulated over real DDS by two processes that follow the lockstep step protocol of
docs/architecture.md: this process plays the sim (publishes TaskState k, waits for both
commands stamped with state k's stamp), a child process plays agent and human (answers every
state with both WrenchStamped commands, a HumanAction and an AgentStep); at the end of each
episode an EpisodeSummary and a SessionStatus follow. The recorder node runs as its own
process, exactly as the session runner starts it. Physics and PPO are not in the loop, so the
steps/s are an upper bound of the message path; the whole graph is measured by the session
benchmark.

    source scripts/env.sh
    python bench/recorder_overhead.py --episodes 5 --steps 200
"""

import argparse
import json
import os
import pathlib
import signal
import subprocess
import sys
import tempfile
import time

import rclpy
from geometry_msgs.msg import WrenchStamped
from hrc_common import qos, topics
from hrc_common.executables import executable_path
from hrc_msgs.msg import AgentStep, EpisodeSummary, HumanAction, SessionStatus, TaskState
from rclpy.executors import SingleThreadedExecutor

CLOCK_TICKS = os.sysconf('SC_CLK_TCK')


def cpu_seconds(pid: int) -> float:
    """Return user + system CPU seconds of a process (Linux /proc)."""
    fields = pathlib.Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS


def run_actors(steps_expected: int) -> None:
    """Child process: answer every state with the commands of both actors."""
    rclpy.init()
    node = rclpy.create_node('bench_actors')
    robot = node.create_publisher(WrenchStamped, topics.ROBOT_CMD_WRENCH, qos.COMMAND_QOS)
    human = node.create_publisher(WrenchStamped, topics.HUMAN_CMD_WRENCH, qos.COMMAND_QOS)
    action = node.create_publisher(HumanAction, topics.HUMAN_ACTION, qos.HUMAN_ACTION_QOS)
    agent = node.create_publisher(AgentStep, topics.AGENT_STEP, qos.AGENT_STEP_QOS)

    def answer(state):
        if state.truncated or state.terminated:
            return
        command = WrenchStamped()
        command.header = state.header
        command.wrench.force.z = 1.0
        robot.publish(command)
        human_command = WrenchStamped()
        human_command.header = state.header
        human_command.wrench.torque.x = 0.1
        human.publish(human_command)
        action.publish(HumanAction(header=state.header, episode=state.episode, step=state.step,
                                   command=0.05, dof=1, source=2, source_detail='bench',
                                   engaged=True))
        agent.publish(AgentStep(header=state.header, episode=state.episode, step=state.step,
                                action=0.1, wrench=1.0, subtask_ids=['slider', 'pendulum'],
                                reward_components=[0.9, 0.8], reward=1.7))

    node.create_subscription(TaskState, topics.STATE, answer, qos.STATE_QOS)
    try:
        rclpy.spin(node)
    except KeyboardInterrupt:
        pass


def run_sim(episodes: int, steps: int) -> dict:
    """Play the lockstep sim for ``episodes`` x ``steps``; return the measured rates."""
    node = rclpy.create_node('bench_sim')
    state_publisher = node.create_publisher(TaskState, topics.STATE, qos.STATE_QOS)
    session_publisher = node.create_publisher(SessionStatus, topics.SESSION, qos.SESSION_QOS)
    summary_publisher = node.create_publisher(EpisodeSummary, topics.EPISODE, qos.EPISODE_QOS)
    answered = {'robot': None, 'human': None}
    node.create_subscription(WrenchStamped, topics.ROBOT_CMD_WRENCH,
                             lambda message: answered.__setitem__('robot', message.header.stamp),
                             qos.COMMAND_QOS)
    node.create_subscription(WrenchStamped, topics.HUMAN_CMD_WRENCH,
                             lambda message: answered.__setitem__('human', message.header.stamp),
                             qos.COMMAND_QOS)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    deadline = time.monotonic() + 30
    while state_publisher.get_subscription_count() < 1 and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
    time.sleep(1.0)
    sim_time = 0.0
    start = time.perf_counter()
    for episode in range(episodes):
        session_publisher.publish(SessionStatus(session_id='bench', case_id=1, episode=episode))
        for step in range(steps + 1):
            state = TaskState(episode=episode, step=step, truncated=step == steps)
            seconds = int(sim_time)
            state.header.stamp.sec = seconds
            state.header.stamp.nanosec = int(round((sim_time - seconds) * 1e9))
            state_publisher.publish(state)
            sim_time += 0.2
            if state.truncated:
                break
            waited = time.monotonic()
            while not all(stamp == state.header.stamp for stamp in answered.values()):
                executor.spin_once(timeout_sec=0.01)
                if time.monotonic() - waited > 5.0:
                    raise RuntimeError(f'no answer to step {step} of episode {episode}')
        summary_publisher.publish(EpisodeSummary(session_id='bench', episode=episode,
                                                 steps=steps, truncated=True))
    elapsed = time.perf_counter() - start
    node.destroy_node()
    return {'steps': episodes * steps, 'seconds': elapsed,
            'steps_per_second': episodes * steps / elapsed}


def start_recorder(output_dir: str, env: dict, changes=()) -> subprocess.Popen:
    command = [str(executable_path('hrc_bag', 'recorder_node')), '--ros-args', '-p',
               f'output_dir:={output_dir}', '-p', 'session_id:=bench']
    for change in changes:                  # NAME=VALUE: a parameter other than its default
        command += ['-p', change.replace('=', ':=', 1)]
    return subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.STDOUT, start_new_session=True)


def measure(episodes: int, steps: int, with_recorder: bool, output_dir: str,
            changes=()) -> dict:
    """Run the emulated lockstep graph once; return rates, recorder CPU and file sizes."""
    env = dict(os.environ)
    actors = subprocess.Popen([sys.executable, __file__, '--actors'], env=env,
                              start_new_session=True)
    recorder = start_recorder(output_dir, env, changes) if with_recorder else None
    rclpy.init()
    try:
        time.sleep(3.0)                     # processes start (the ROS wheels re-exec once)
        cpu_before = cpu_seconds(recorder.pid) if recorder else 0.0
        result = run_sim(episodes, steps)
        time.sleep(1.0)                     # the recorder closes the last episode file
        if recorder:
            result['recorder_cpu_seconds'] = cpu_seconds(recorder.pid) - cpu_before
            result['recorder_cpu_percent'] = 100.0 * result['recorder_cpu_seconds'] / (
                result['seconds'] + 1.0)
    finally:
        rclpy.shutdown()
        os.killpg(actors.pid, signal.SIGINT)
        actors.wait(timeout=10)
        if recorder:
            os.killpg(recorder.pid, signal.SIGINT)
            result['recorder_exit_code'] = recorder.wait(timeout=20)
    if recorder:
        files = sorted(pathlib.Path(output_dir, 'bench').glob('bench_episode*.mcap'))
        result['files'] = [path.name for path in files]
        sizes = [path.stat().st_size for path in files]
        result['episode_files'] = len(files)
        result['bytes_per_episode'] = sum(sizes) / len(sizes) if sizes else 0
        messages = episodes * (steps * 5 + 2)
        result['recorder_cpu_us_per_message'] = 1e6 * result['recorder_cpu_seconds'] / messages
    return result


def main(argv=None) -> int:
    """Run the benchmark and print the numbers (and JSON with --json)."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--episodes', type=int, default=5)
    parser.add_argument('--steps', type=int, default=200, help='control steps per episode')
    parser.add_argument('--json', help='also write the results to this file')
    parser.add_argument('--keep', help='record into this folder (kept) instead of a temporary '
                        'one')
    parser.add_argument('--set', action='append', default=[], metavar='NAME=VALUE',
                        help='a recorder parameter other than its default')
    parser.add_argument('--actors', action='store_true', help=argparse.SUPPRESS)
    arguments = parser.parse_args(argv)
    if arguments.actors:
        run_actors(0)
        return 0
    with tempfile.TemporaryDirectory(prefix='hrc_bag_bench_') as output_dir:
        output_dir = arguments.keep or output_dir
        without = measure(arguments.episodes, arguments.steps, False, output_dir)
        with_recorder = measure(arguments.episodes, arguments.steps, True, output_dir,
                                arguments.set)
    results = {'without_recorder': without, 'with_recorder': with_recorder}
    print(f'lockstep message path, {arguments.episodes} episodes x {arguments.steps} steps, '
          f'recorder parameters changed: {arguments.set or "none"}:')
    print(f'  without recorder: {without["steps_per_second"]:8.1f} steps/s')
    print(f'  with recorder:    {with_recorder["steps_per_second"]:8.1f} steps/s')
    print(f'  recorder CPU:     {with_recorder["recorder_cpu_percent"]:8.1f} % of one core, '
          f'{with_recorder["recorder_cpu_us_per_message"]:.0f} us per message')
    print(f'  bytes per episode: {with_recorder["bytes_per_episode"]:.0f} '
          f'({with_recorder["episode_files"]} files, zstd chunks)')
    if arguments.json:
        pathlib.Path(arguments.json).write_text(json.dumps(results, indent=2))
    return 0


if __name__ == '__main__':
    sys.exit(main())
