#!/usr/bin/env python3
"""How long a person waits in task first while the robot learns alone, through the graph.

    python bench/person_wait.py                                   # the default learning, 3 runs
    python bench/person_wait.py --repeats 2 -- --learning ppo     # more session options

Runs ``hrc session --case 2 --mode realtime`` (the graph: sim, agent, simulated human, recorder
as processes over DDS; the robot-alone episodes of a realtime session run in lockstep, as fast
as the graph goes) and times, from the command's start, the episode line at which the robot's
alone step converged: what the person at the joystick waits before the first joint episode.
Then the session is stopped (SIGINT). Prints per run: that time, the start-up (to the first
episode's line, which comes when episode 0 ends), the robot-alone episodes, and at the end the
median [min, max] over the runs.

Settings: the session's defaults (the default learning configuration, what ``make run``
uses); anything after ``--`` is passed to ``hrc session``.
"""

import argparse
import collections
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time


def one_run(arguments: list, timeout: float) -> dict:
    """Run one session until its robot-alone step converged; return the times (s)."""
    started = time.monotonic()
    process = subprocess.Popen(['hrc', 'session', '--case', '2', '--mode', 'realtime',
                                *arguments], stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, start_new_session=True)
    first_line = None
    episodes = 0
    last_lines = collections.deque(maxlen=8)
    result = {'converged': None, 'first_line': None, 'episodes': 0, 'line': ''}
    # A session that hangs silently (no line) is stopped all the same.
    watchdog = threading.Timer(timeout, os.killpg, (process.pid, signal.SIGINT))
    watchdog.start()
    try:
        for line in process.stdout:
            now = time.monotonic() - started
            last_lines.append(line.rstrip())
            if '| episode' not in line:
                continue
            first_line = now if first_line is None else first_line
            if 'step 1/' not in line:
                break      # the person's step began without a converged robot-alone step
            episodes += 1
            if 'converged' in line:
                result.update(converged=now, line=line.strip())
                break
    finally:
        watchdog.cancel()
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGINT)
        try:
            process.communicate(timeout=30)    # reads on: a long report cannot block the runner
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.communicate()
    result.update(first_line=first_line, episodes=episodes, exit_code=process.returncode,
                  last_lines=list(last_lines))
    return result


def main(argv=None) -> int:
    """Run the sessions and print the times; return 0 (1 when a run never converged)."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--repeats', type=int, default=3, help='sessions run in turn (default 3)')
    parser.add_argument('--timeout', type=float, default=600.0,
                        help='give up on a run after this many seconds (default 600)')
    parser.add_argument('session_options', nargs='*',
                        help='more `hrc session` options, after --')
    args = parser.parse_args(argv)
    if args.repeats < 1 or args.timeout <= 0:
        print('person_wait: --repeats must be >= 1 and --timeout > 0', file=sys.stderr)
        return 2
    if shutil.which('hrc') is None:
        print('person_wait: `hrc` is not on the PATH: run `source scripts/env.sh` first',
              file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix='person-wait-') as scratch:
        arguments = ['--runs-dir', f'{scratch}/runs', '--bags-dir', f'{scratch}/bags',
                     *args.session_options]
        print(f'person_wait: hrc session --case 2 --mode realtime {" ".join(arguments)}',
              flush=True)
        waits = []
        for run in range(args.repeats):
            result = one_run(arguments, args.timeout)
            if result['first_line'] is None and result['exit_code'] not in (0, None, -2):
                print(f'person_wait: the session ended with exit code {result["exit_code"]} '
                      'before its first episode:\n  ' + '\n  '.join(result['last_lines']),
                      file=sys.stderr)
                return 2
            if result['converged'] is None:
                print(f'  run {run + 1}: the robot-alone step did not converge '
                      f'({result["episodes"]} episodes)', flush=True)
                continue
            waits.append(result['converged'])
            print(f'  run {run + 1}: robot-alone step converged {result["converged"]:.1f} s '
                  f'after the start: start-up and episode 0 {result["first_line"]:.1f} s, '
                  f'{result["episodes"]} robot-alone episodes', flush=True)
    if not waits:
        return 1
    print(f'person_wait: the person waited median {statistics.median(waits):.1f} s '
          f'[{min(waits):.1f}, {max(waits):.1f}] over {len(waits)} runs')
    return 0 if len(waits) == args.repeats else 1


if __name__ == '__main__':
    sys.exit(main())
