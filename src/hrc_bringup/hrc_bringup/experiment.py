"""Experiment runner: the six paper cases x N seeds, headless, then the report across all.

    ros2 run hrc_bringup experiment --seeds 1 --parallel 2

Each session is a separate ``session`` process on its own ROS_DOMAIN_ID, so sessions that run
in parallel never see each other. The report then reads every session's bags together and gives
Table II with the spread across seeds and Fig. 5-7.
"""

import argparse
import pathlib
import subprocess
import sys
import time

from hrc_bringup.supervisor import describe_exit
from hrc_common.contract import case_problem, make_session_id


def parse_args(argv=None):
    """Parse the command line."""
    parser = argparse.ArgumentParser(
        prog='experiment', description='Run paper cases x seeds headless with the simulated '
        'human (sessions in parallel on separate ROS domains), then the report across all.')
    parser.add_argument('--cases', type=int, nargs='+', default=[1, 2, 3, 4, 5, 6],
                        help='cases to run (default 1 2 3 4 5 6)')
    parser.add_argument('--seeds', type=int, default=1, help='seeds per case (0..N-1)')
    parser.add_argument('--first-seed', type=int, default=0, help='first seed (default 0)')
    parser.add_argument('--parallel', type=int, default=2,
                        help='sessions at once (default 2, one per core)')
    parser.add_argument('--name', default='', help='experiment name (default: time)')
    parser.add_argument('--bags-dir', default='bags', help='root of the bags')
    parser.add_argument('--runs-dir', default='runs', help='root of logs and reports')
    parser.add_argument('--first-domain-id', type=int, default=40,
                        help='ROS_DOMAIN_ID of the first parallel slot (default 40)')
    parser.add_argument('--session-arg', action='append', default=[],
                        help='extra argument passed to every session (repeatable), e.g. '
                        '--session-arg=--episodes=30')
    options = parser.parse_args(argv)
    problems = [case_problem(case) for case in options.cases if case_problem(case)]
    if problems:
        parser.error('; '.join(problems))
    if options.seeds < 1 or options.parallel < 1:
        parser.error('--seeds and --parallel must be >= 1')
    return options


def main(argv=None) -> int:
    """Entry point of ``ros2 run hrc_bringup experiment``."""
    from hrc_common.executables import executable_path

    options = parse_args(argv)
    name = options.name or time.strftime('experiment-%Y%m%d-%H%M%S')
    runs_dir = pathlib.Path(options.runs_dir) / name
    bags_dir = pathlib.Path(options.bags_dir) / name
    runs_dir.mkdir(parents=True, exist_ok=True)
    jobs = [(case, seed) for seed in range(options.first_seed, options.first_seed + options.seeds)
            for case in options.cases]
    print(f'[experiment] {name}: {len(jobs)} sessions ({len(options.cases)} cases x '
          f'{options.seeds} seeds), {options.parallel} at a time; bags in {bags_dir}',
          flush=True)
    session = str(executable_path('hrc_bringup', 'session'))
    running = {}
    results = {}
    free_slots = list(range(options.parallel))
    start = time.monotonic()
    try:
        while jobs or running:
            while jobs and free_slots:
                case, seed = jobs.pop(0)
                slot = free_slots.pop(0)
                session_id = make_session_id(case, seed, timestamped=False)
                log = open(runs_dir / f'{session_id}.log', 'wb')
                command = [session, '--case', str(case), '--seed', str(seed),
                           '--session-id', session_id, '--bags-dir', str(bags_dir),
                           '--runs-dir', str(runs_dir), '--no-report',
                           '--domain-id', str(options.first_domain_id + slot),
                           *options.session_arg]
                process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)
                running[session_id] = (process, slot, log, time.monotonic())
                print(f'[experiment] started {session_id} (domain '
                      f'{options.first_domain_id + slot})', flush=True)
            time.sleep(0.5)
            for session_id, (process, slot, log, started) in list(running.items()):
                if process.poll() is None:
                    continue
                log.close()
                del running[session_id]
                free_slots.append(slot)
                results[session_id] = process.returncode
                print(f'[experiment] {session_id} finished in {time.monotonic() - started:.0f} s'
                      f' ({describe_exit(process.returncode)})', flush=True)
    except KeyboardInterrupt:
        print('[experiment] interrupted: stopping the running sessions', flush=True)
        for process, _, _, _ in running.values():
            process.send_signal(2)
        for process, _, _, _ in running.values():
            process.wait()
        return 130
    elapsed = time.monotonic() - start
    failed = sorted(session_id for session_id, code in results.items() if code != 0)
    print(f'[experiment] {len(results)} sessions in {elapsed:.0f} s wall'
          + (f'; failed: {failed}' if failed else ''), flush=True)
    report_dir = runs_dir / 'report'
    report = subprocess.run([str(executable_path('hrc_bag', 'hrc_report')),
                             *sorted(str(path) for path in bags_dir.iterdir() if path.is_dir()),
                             '--out', str(report_dir)], capture_output=True, text=True)
    print(report.stdout, end='')
    if report.returncode != 0:
        print(f'[experiment] report failed:\n{report.stderr}', file=sys.stderr)
        return 1
    print(f'[experiment] report and figures: {report_dir}', flush=True)
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
