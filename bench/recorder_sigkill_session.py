#!/usr/bin/env python3
"""SIGKILL the recorder of a real lockstep session (sim, agent, simulated human) at random moments.

Each trial runs ``session --mode lockstep`` (the session runner, every node its own process)
on a domain id of its own, listens to ``/hrc/episode`` from this process to learn when each
EpisodeSummary was sent (wall clock at reception), and kills the runner's recorder_node with
SIGKILL at a random moment. Then the runner is stopped, the files the recorder left open are
finished by recovery, and each episode whose summary was heard more than ``--finished`` s
before the kill is checked: its file closed before the kill (listed in metadata.yaml) and
whole (every state, command, human action and agent step of the episode, and its summary).

    source scripts/env.sh
    python bench/recorder_sigkill_session.py --trials 5
"""

import argparse
import os
import pathlib
import random
import signal
import subprocess
import sys
import tempfile
import threading
import time

import rclpy
from hrc_bag import bag_reader
from hrc_bag.recovery import recover_file
from hrc_common import qos, topics
from hrc_common.proc_tree import descendants
from hrc_msgs.msg import EpisodeSummary


def recorder_of(runner_pid: int):
    """Return the pid of the runner's recorder_node process (None if not running)."""
    for pid in descendants(runner_pid):
        try:
            command = pathlib.Path(f'/proc/{pid}/cmdline').read_bytes().split(b'\0')
        except OSError:
            continue
        if any(part.endswith(b'recorder_node') for part in command[:2]):
            return pid
    return None


def check_episode(folder, name, summary_steps, human_involved) -> list:
    """Return what episode file ``name`` lacks (empty when whole).

    The human's topics are expected only in episodes with the human involved: a human who sits
    out sends nothing.
    """
    counts = {}
    for message in bag_reader.scan_file(pathlib.Path(folder) / name).messages:
        counts[message.topic] = counts.get(message.topic, 0) + 1
    expected = {'/hrc/state': summary_steps + 1, '/hrc/robot/cmd_wrench': summary_steps,
                '/hrc/agent/step': summary_steps, '/hrc/episode': 1}
    if human_involved:
        expected.update({'/hrc/human/cmd_wrench': summary_steps,
                         '/hrc/human/action': summary_steps})
    return [f'{topic} {counts.get(topic, 0)}/{count}' for topic, count in expected.items()
            if counts.get(topic, 0) < count]


def trial(number: int, kill_after: float, finished: float, episodes: int, work: str,
          domain_id: int, changes=()) -> dict:
    """Run one session, kill its recorder after ``kill_after`` s of episodes, check the bags."""
    session_id = f'kill{number}'
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               FASTDDS_BUILTIN_TRANSPORTS='UDPv4', PYTHONUNBUFFERED='1')
    os.environ.update(ROS_DOMAIN_ID=str(domain_id), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
                      FASTDDS_BUILTIN_TRANSPORTS='UDPv4')
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node('sigkill_listener', context=context)
    heard = {}                              # episode -> (wall ns, steps, human involved)
    node.create_subscription(EpisodeSummary, topics.EPISODE,
                             lambda message: heard.setdefault(
                                 message.episode, (time.time_ns(), message.steps,
                                                   message.human_involved)),
                             qos.EPISODE_QOS)
    executor = rclpy.executors.SingleThreadedExecutor(context=context)
    executor.add_node(node)
    spinning = threading.Thread(target=executor.spin, daemon=True)
    spinning.start()
    log = open(os.path.join(work, f'{session_id}.log'), 'w')
    runner = subprocess.Popen(
        [sys.executable, '-m', 'hrc_bringup.session', '--case', '1', '--mode', 'lockstep',
         '--episodes', str(episodes), '--eval-episodes', '0', '--session-id', session_id,
         '--bags-dir', os.path.join(work, 'bags'), '--runs-dir', os.path.join(work, 'runs'),
         '--domain-id', str(domain_id), '--no-report',
         *[part for change in changes for part in ('--set', f'recorder.{change}')]],
        env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while not heard and time.monotonic() < deadline:     # the first episode is done
            time.sleep(0.05)
        if not heard:
            raise RuntimeError(f'no episode in 120 s; see {log.name}')
        time.sleep(kill_after)
        recorder = recorder_of(runner.pid)
        if recorder is None:
            raise RuntimeError('the recorder is not running')
        kill_ns = time.time_ns()
        os.kill(recorder, signal.SIGKILL)
        time.sleep(1.0)
    finally:
        if runner.poll() is None:
            os.killpg(runner.pid, signal.SIGINT)
            try:
                runner.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(runner.pid, signal.SIGKILL)
                runner.wait(timeout=10)
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown(context=context)
        log.close()
    return examine(pathlib.Path(work, 'bags', session_id), session_id, heard, kill_ns, finished)


def examine(folder: pathlib.Path, session_id: str, heard: dict, kill_ns: int,
            finished: float) -> dict:
    """Return what the kill at ``kill_ns`` cost: the episodes heard ``finished`` s before it."""
    closed = bag_reader.read_bag_metadata_yaml(folder).get('relative_file_paths') or []
    problems = {}
    done = {episode: info for episode, info in heard.items()
            if kill_ns - info[0] > finished * 1e9}
    for episode, (_, steps, human_involved) in sorted(done.items()):
        name = f'{session_id}_episode{episode + 1:04d}.mcap'
        if name not in closed:
            problems[episode] = ['not closed before the kill']
        else:
            lacking = check_episode(folder, name, steps, human_involved)
            if lacking:
                problems[episode] = lacking
    # the open episode: finished by recovery; how much before the kill is missing
    newest = 0
    for path in sorted(folder.glob('*.mcap')):
        if path.name not in closed:
            recover_file(path)
        for message in bag_reader.scan_file(path).messages:
            if message.log_time <= kill_ns:
                newest = max(newest, message.log_time)
    waiting = [kill_ns - info[0] for episode, info in heard.items()
               if info[0] < kill_ns
               and f'{session_id}_episode{episode + 1:04d}.mcap' not in closed]
    return {'episodes_heard': len([e for e, info in heard.items() if info[0] < kill_ns]),
            'checked': len(done), 'problems': problems,
            'newest_recorded_before_kill': (kill_ns - newest) / 1e9 if newest else None,
            'unclosed_after': max(waiting, default=0) / 1e9}


def main(argv=None) -> int:
    """Run the trials and print what each kill cost."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--trials', type=int, default=5)
    parser.add_argument('--seed', type=int, default=3)
    parser.add_argument('--episodes', type=int, default=30, help='training episodes a session')
    parser.add_argument('--finished', type=float, default=0.75,
                        help='an episode counts as finished when its summary was heard this '
                             'long (s) before the kill')
    parser.add_argument('--domain-id', type=int, default=143)
    parser.add_argument('--set', action='append', default=[], metavar='NAME=VALUE',
                        help='a recorder parameter other than its default')
    arguments = parser.parse_args(argv)
    chance = random.Random(arguments.seed)
    whole = True
    with tempfile.TemporaryDirectory(prefix='hrc_sigkill_session_') as work:
        for number in range(arguments.trials):
            result = trial(number, chance.uniform(0.5, 6.0), arguments.finished,
                           arguments.episodes, work, arguments.domain_id, arguments.set)
            whole = whole and not result['problems']
            gap = result['newest_recorded_before_kill']
            print(f'trial {number}: {result["episodes_heard"]:2d} episodes finished before the '
                  f'kill, {result["checked"]:2d} of them {arguments.finished} s before it; '
                  f'problems: {result["problems"] or "none"}; newest message kept was received '
                  f'{gap * 1000 if gap is not None else float("nan"):.0f} ms before the kill; '
                  f'oldest summary not closed {result["unclosed_after"] * 1000:.0f} ms',
                  flush=True)
    print(f'recorder parameters changed: {arguments.set or "none"}; every episode finished '
          f'{arguments.finished} s before a kill was closed and whole: {whole}')
    return 0 if whole else 1


if __name__ == '__main__':
    sys.exit(main())
