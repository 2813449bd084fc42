#!/usr/bin/env python3
"""Measure what a SIGKILL of the recorder loses during a lockstep-paced session.

Each trial starts a recorder node (defaults of params/recorder.yaml), sends a first episode,
then episodes of ``--steps`` states ``--step-period`` s apart (five messages per step, as the
graph in lockstep: state, two commands, human action, agent step; a summary per episode) and
kills the recorder with SIGKILL at a random moment (seeded). Files left open are finished by
recovery. Printed per trial and as a summary:

* loss: kill time minus the send time of the oldest message missing from the bags (the part
  of the open episode that was lost);
* unclosed: the longest time a sent EpisodeSummary waited at the kill without its file being
  closed (how soon after its last message a finished episode is durable);
* whether every closed episode holds all its messages.

    source scripts/env.sh
    python bench/recorder_sigkill.py --trials 20
"""

import argparse
import os
import pathlib
import random
import statistics
import sys
import tempfile

import rclpy

# The test support (test/support/hrc_testing) is not installed: found from the checkout.
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'test' / 'support'))
from hrc_testing.bag_traffic import SyntheticSession  # noqa: E402 (after the path)
from hrc_testing.recorder_kill import kill_trial  # noqa: E402 (after the path)
from hrc_testing.nodes import NodeProcess, ros_environment  # noqa: E402 (after the path)


def main(argv=None) -> int:
    """Run the trials and print the measured loss windows."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--trials', type=int, default=20)
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--steps', type=int, default=25, help='states per episode')
    parser.add_argument('--step-period', type=float, default=0.01, help='s between states')
    parser.add_argument('--set', action='append', default=[], metavar='NAME=VALUE',
                        help='a recorder parameter other than its default (e.g. the old '
                             'flush_period=1.0 close_grace=0.5 reorder_window=0.5)')
    parser.add_argument('--domain-id', type=int, default=int(os.environ.get('ROS_DOMAIN_ID',
                                                                            '0') or 0) or 97)
    arguments = parser.parse_args(argv)

    env = ros_environment(arguments.domain_id)
    os.environ.update(env)              # this process's participant joins the same domain

    rclpy.init()
    node = rclpy.create_node('sigkill_bench')
    chance = random.Random(arguments.seed)
    changes = dict(item.split('=', 1) for item in arguments.set)
    losses, waits = [], []
    whole = True
    undelivered = 0
    with tempfile.TemporaryDirectory(prefix='hrc_sigkill_') as output_dir:
        for trial in range(arguments.trials):
            prefix = f'/b{os.getpid()}_{trial}'
            remaps = []
            for topic in ('/hrc/state', '/hrc/robot/cmd_wrench', '/hrc/human/cmd_wrench',
                          '/hrc/human/action', '/hrc/session', '/hrc/episode',
                          '/hrc/agent/step'):
                remaps += ['-r', f'{topic}:={prefix}{topic}']
            recorder = NodeProcess('hrc_bag', 'recorder_node', env=env, ros_args=remaps,
                                   parameters={'output_dir': output_dir,
                                               'session_id': f'trial{trial}', **changes})
            session = SyntheticSession(node, f'trial{trial}', seed=trial, prefix=prefix)
            if not session.wait_for_subscribers():
                print(f'trial {trial}: the recorder did not subscribe\n{recorder.output}')
                return 1
            result = kill_trial(session, recorder.process.pid,
                                os.path.join(output_dir, f'trial{trial}'),
                                chance.uniform(1.2, 3.0), arguments.steps,
                                arguments.step_period)
            recorder.process.wait(timeout=10)
            losses.append(result.loss)
            waits.append(result.unclosed_after)
            whole = whole and not result.misplaced
            undelivered += len(result.undelivered)
            print(f'trial {trial:2d}: {len(result.summaries):2d} episodes finished, '
                  f'{len(result.closed):2d} files closed, loss {result.loss * 1000:6.0f} ms, '
                  f'oldest unclosed summary {result.unclosed_after * 1000:5.0f} ms',
                  flush=True)
            for episode, topics in sorted(result.misplaced.items()):
                print(f'          episode {episode}: messages in another file on '
                      f'{", ".join(topics)}')
            for episode, topics in sorted(result.undelivered.items()):
                print(f'          episode {episode}: DDS did not deliver every message on '
                      f'{", ".join(topics)}')
            for publisher in session.publishers.values():
                node.destroy_publisher(publisher)
    print(f'\n{arguments.trials} kills, episodes of {arguments.steps} steps '
          f'{arguments.step_period * 1000:g} ms apart, recorder parameters changed: '
          f'{changes or "none"}:')
    print(f'  loss of the open episode: median {statistics.median(losses) * 1000:.0f} ms, '
          f'max {max(losses) * 1000:.0f} ms')
    print(f'  a finished episode waited for its close at most {max(waits) * 1000:.0f} ms '
          f'(median over kills {statistics.median(waits) * 1000:.0f} ms)')
    print(f'  every closed episode holds all its recorded messages: {whole}; episodes with '
          f'messages DDS never delivered to the recorder: {undelivered}')
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
