"""Experiment runner: paper cases x seeds (x simulated-human profiles), headless, then the study.

    hrc experiment --seeds 10                       # local process pool
    hrc experiment --seeds 10 --profiles paper paper_symmetric:5
    hrc experiment --seeds 10 --ray                 # a local Ray instance
    hrc experiment --seeds 10 --ray-address auto    # an existing Ray cluster
    hrc experiment --seeds 2 --engine graph         # the ROS graph per session

Each session (case, seed, profile) is one task (``hrc_bringup.experiment_task``) submitted to
an executor: a local process pool (the embedded default, no Ray needed) or Ray, with declared
resources (``--cpus-per-session``). A task runs the session with the chosen engine:

* ``inprocess``: ``hrc_engine.run_session`` in the worker process (sim, agent, simulated human
  in one process, same cores as the graph, same bags);
* ``graph``: the ``session`` runner (sim, agent, human, recorder as processes over DDS) on a ROS
  domain reserved on the worker's machine (lock files of hrc_common.domains.DomainReservation,
  shared with the tests), so concurrent sessions on one node never see each other.

Cases 7 and 8 (``partners_first``) first train with a simulated population in the worker
(``hrc_partners.partners_first.prepare_person_session``: the robot alone, then the population,
no person, a record in the session's run folder, ``pretrain.json``); the session with its
simulated person then starts from that checkpoint, in either engine.

Bags land in ``<bags-dir>/<name>/<session_id>`` as seen from the worker: on a cluster that is a
shared filesystem, or with ``--pull-bags`` each task packs its session folder and the driver
unpacks it here (docs/sweeps.md). Every session's outcome and the sweep's wall time go to
``<bags-dir>/<name>/experiment.json``; then ``hrc_study`` writes the report of all sessions
(``<runs-dir>/<name>/report/results.md``).

Exit codes: 0 every session done, 1 a session failed or the report failed, 2 bad arguments,
130 interrupted.
"""

from dataclasses import asdict
import json
import os
import pathlib
import shlex
import signal
import subprocess
import sys
import time

from hrc_common import paths
from hrc_common.cases import case_problem
from hrc_common.session_plan import package_version, parse_overrides, SessionSettings
from hrc_common.time_left import TimeLeft

from hrc_bringup.experiment_args import build_parser
from hrc_bringup.experiment_resume import (earlier_files, finished_sessions, JOURNAL_NAME,
                                           journal_line, set_aside,
                                           kept_runs, MANIFEST_NAME, split_resumed)
from hrc_bringup.experiment_task import (lost_outcome, run_task, session_id_of, SessionTask,
                                         unpack_folder)
from hrc_bringup.local_pool import LocalPool, WAKE_PERIOD_S

# s: how often the sweep's main thread wakes while it waits for sessions (signal handling)


class RayExecutor:
    """Ray: an existing cluster (``address``) or a local instance started here (None)."""

    def __init__(self, address, cpus_per_session: float, function=run_task, lost=lost_outcome):
        """Connect; ``function(task)`` runs a task, ``lost(task, how, seconds)`` reports a death.

        ``lost`` gives the outcome of a task whose worker died, as :class:`LocalPool`'s does.
        """
        import ray  # lazy: optional heavy dependency, only the --ray executor needs it
        self.ray = ray
        ray.init(address=address, include_dashboard=False, log_to_driver=False,
                 logging_level='ERROR', configure_logging=True)
        self.remote = ray.remote(num_cpus=cpus_per_session, max_retries=0)(function)
        self.cpus_per_session = cpus_per_session
        self.lost = lost

    def describe(self) -> str:
        """Return what runs the tasks."""
        nodes = [node for node in self.ray.nodes() if node.get('Alive')]
        cpus = self.ray.cluster_resources().get('CPU', 0)
        return (f'Ray cluster ({len(nodes)} nodes, {cpus:g} CPUs, {self.cpus_per_session:g} '
                f'CPU per session)')

    def run(self, tasks, on_done):
        """Run every task; call ``on_done(outcome)`` as each finishes.

        A task whose worker died (killed, out of memory, its node lost) is reported as lost
        with Ray's reason; the other tasks go on.
        """
        task_of = {self.remote.remote(task): task for task in tasks}
        pending = list(task_of)
        while pending:
            # woken every WAKE_PERIOD_S, so that Ctrl-C or SIGTERM is handled (LocalPool.run)
            done, pending = self.ray.wait(pending, num_returns=1, timeout=WAKE_PERIOD_S)
            for reference in done:
                try:
                    outcome = self.ray.get(reference)
                except self.ray.exceptions.RayError as error:
                    reason = str(error).strip().splitlines()[0] if str(error).strip() else ''
                    outcome = self.lost(task_of[reference], f'its Ray worker died '
                                        f'({type(error).__name__}: {reason})', 0.0)
                on_done(outcome)

    def close(self, abort: bool = False):
        """Disconnect (a local instance started here stops with it, and its tasks)."""
        self.ray.shutdown()


def parse_args(argv=None):
    """Parse and check the command line (exit 2 with every reason)."""
    parser = build_parser()
    options = parser.parse_args(argv)
    reasons = [problem for problem in map(case_problem, options.cases) if problem]
    if options.seeds < 1:
        reasons.append(f'--seeds must be >= 1, got {options.seeds}')
    if options.parallel < 0:
        reasons.append(f'--parallel must be >= 0, got {options.parallel}')
    if options.stop_after < 0:
        reasons.append(f'--stop-after must be >= 0, got {options.stop_after}')
    if options.cpus_per_session <= 0:
        reasons.append(f'--cpus-per-session must be > 0, got {options.cpus_per_session}')
    if options.ray and options.ray_address:
        reasons.append('--ray starts a local instance; --ray-address joins one: give one')
    options.profile_seeds = {}
    for text in options.profiles:
        profile, colon, count = text.partition(':')
        if colon and not (count.isdigit() and int(count) >= 1):
            reasons.append(f'--profiles {text!r}: seeds after ":" must be an integer >= 1')
            continue
        if profile in options.profile_seeds:
            reasons.append(f'--profiles repeats {profile!r}')
        options.profile_seeds[profile] = int(count) if colon else options.seeds
    try:
        parse_overrides(options.overrides)
    except ValueError as error:
        reasons.append(str(error))
    if reasons:
        parser.error('; '.join(reasons))
    options.argv = list(sys.argv[1:] if argv is None else argv)
    return options


def plan_tasks(options, bags_dir: pathlib.Path, runs_dir: pathlib.Path) -> list:
    """Return the sweep's tasks: profiles x seeds x cases, in the order they should run.

    Profiles advance in proportion to their seed counts (seed s of a profile with n seeds at
    s / n), so a sweep cut short by --stop-after holds whole seeds (all cases) of every
    profile, the first profile first.
    """
    # resolved here, so that every worker reads the same files (a checkout's params/ when the
    # driver runs in one; on a cluster the same path, or the installed share/, on every node)
    params_dir = str((pathlib.Path(options.params_dir) if options.params_dir
                      else paths.params_dir()).resolve())
    not_after = time.time() + 60 * options.stop_after if options.stop_after else 0.0
    order = list(options.profile_seeds)
    planned = sorted(((seed_index / seeds, order.index(profile), seed_index, profile)
                      for profile, seeds in options.profile_seeds.items()
                      for seed_index in range(seeds)))
    return [SessionTask(
        SessionSettings(case=case, seed=options.first_seed + seed_index, human_profile=profile,
                        learning=options.learning,
                        session_id=(session_id := session_id_of(
                            case, options.first_seed + seed_index, profile, order)),
                        bags_dir=str(bags_dir.resolve()),
                        runs_dir=str(runs_dir.resolve() / session_id),
                        training_episodes=options.episodes,
                        evaluation_episodes=options.eval_episodes,
                        overrides=parse_overrides(
                            person_override(options, options.first_seed + seed_index)
                            + tuple(options.overrides))),
        engine=options.engine, params_dir=params_dir, pull_bags=options.pull_bags,
        checkpoints=options.checkpoints, not_after=not_after)
        for _, _, seed_index, profile in planned
        for case in options.cases]


def resume_plan(options, bags_dir: pathlib.Path, planned: list, version: str) -> tuple:
    """Return ``(earlier runs, reused, tasks to run)`` (``--resume``; else nothing reused).

    ``reused`` pairs each planned task an earlier run of the folder finished with that run's
    record; the earlier runs are those whose sessions are kept (both:
    hrc_bringup.experiment_resume).
    """
    if not options.resume:
        return [], [], planned
    finished = finished_sessions(bags_dir)
    reused, tasks, other_version = split_resumed(
        [(task, asdict(task.settings), task.engine) for task in planned], finished, version)
    if other_version:
        versions = sorted({record['version'] for _, record in other_version})
        print(f'[experiment] resume: {len(other_version)} finished sessions of another version '
              f'({", ".join(versions)}) run again at {version}', flush=True)
    if reused and version.endswith('-dirty'):
        print(f'[experiment] resume: the code has uncommitted changes ({version}); the sessions '
              'kept may come from other uncommitted code', flush=True)
    return kept_runs(bags_dir, reused), reused, tasks


def person_override(options, seed: int) -> tuple:
    """Return the override that makes the session's simulated human person number ``seed``.

    Each seed is then a different person drawn from the population around the profile
    (hrc_joystick_node.population.sample_person); ``--same-person`` keeps the profile itself.
    """
    return () if options.same_person else (f'human.person={seed}',)


def make_executor(options):
    """Return the executor the options ask for."""
    if options.ray or options.ray_address:
        return RayExecutor(options.ray_address or None, options.cpus_per_session)
    return LocalPool(options.parallel or os.cpu_count() or 1, lost=lost_outcome)


def main(argv=None) -> int:
    """Entry point of ``hrc experiment``."""
    options = parse_args(argv)
    name = options.name or time.strftime('experiment-%Y%m%d-%H%M%S')
    bags_dir = pathlib.Path(options.bags_dir) / name
    runs_dir = pathlib.Path(options.runs_dir) / name
    bags_dir.mkdir(parents=True, exist_ok=True)
    runs_dir.mkdir(parents=True, exist_ok=True)
    planned = plan_tasks(options, bags_dir, runs_dir)
    version = _version()
    prior_runs, reused, tasks = resume_plan(options, bags_dir, planned, version)
    if not clean_folders(options, name, tasks, runs_dir):
        return 2
    journal = bags_dir / JOURNAL_NAME
    if not options.resume:
        journal.write_text('')     # a new sweep of the folder: its sessions are journalled anew
    uncommitted = _uncommitted_sources()
    started_at = time.strftime('%Y-%m-%d %H:%M:%S %Z')
    start = time.monotonic()
    try:
        executor = make_executor(options)
    except Exception as error:   # Ray not reachable: say so, no traceback
        print(f'[experiment] cannot start the executor: {error}', file=sys.stderr)
        return 1
    announce(options, name, planned, executor, bags_dir, reused, tasks)
    tasks_by_id = {task.session_id: task for task in tasks}
    outcomes = []
    progress = TimeLeft(len(tasks), 'sessions')

    def on_done(outcome):
        archive = outcome.pop('bag_archive', None)
        if archive is not None:
            unpack_folder(archive, bags_dir, outcome['session_id'])
        outcome['finished_after'] = time.monotonic() - start   # s since the sweep started
        outcome['version'] = version
        outcome['run_started'] = started_at
        outcomes.append(outcome)
        if outcome['exit_code'] is None:
            return   # skipped (--stop-after): listed at the end
        with journal.open('a') as lines:     # at once: an interrupted sweep resumes from here
            lines.write(journal_line(asdict(tasks_by_id[outcome['session_id']]), outcome,
                                     version) + '\n')
        status = 'done' if outcome['exit_code'] == 0 else f'FAILED: {outcome["error"]}'
        progress.show(len(outcomes), f'[experiment] {outcome["session_id"]} on '
                      f'{outcome["host"]} in {outcome["seconds"]:.0f} s ({len(outcomes)}/'
                      f'{len(tasks)}): {status}')

    interrupt_on_signals()
    try:
        executor.run(tasks, on_done)
    except KeyboardInterrupt:
        progress.close()
        print('[experiment] interrupted: sessions in progress stopped', flush=True)
        executor.close(abort=True)
        return 130
    progress.close()
    description = executor.describe()
    executor.close()
    wall = time.monotonic() - start
    failed = sorted(outcome['session_id'] for outcome in outcomes
                    if outcome['exit_code'] not in (0, None))
    skipped = sorted(outcome['session_id'] for outcome in outcomes
                     if outcome['exit_code'] is None)
    this_run = {'command': 'hrc experiment ' + ' '.join(shlex.quote(arg) for arg in options.argv),
                'started': started_at, 'wall_seconds': wall, 'version': version,
                'sessions_run': len(outcomes) - len(skipped)}
    record = manifest(options, planned, tasks, reused, outcomes, prior_runs + [this_run],
                      description, uncommitted)
    (bags_dir / MANIFEST_NAME).write_text(json.dumps(record, indent=1))
    cpu = sum(outcome.get('cpu_seconds', 0.0) for outcome in outcomes)
    print(f'[experiment] {len(outcomes) - len(skipped)} sessions in {wall:.0f} s wall '
          f'({wall / 60:.1f} min; {cpu:.0f} CPU s in the sessions)'
          + (f'; {len(reused)} kept from earlier runs' if reused else '')
          + (f'; failed: {failed}' if failed else '')
          + (f'; skipped after --stop-after: {len(skipped)}' if skipped else ''), flush=True)
    if not options.report:
        return 1 if failed else 0
    out = options.report_out or str(runs_dir / 'report')
    from hrc_study import results_cli  # lazy: scipy and matplotlib (seconds), only for --report
    code = results_cli.main([str(bags_dir), '--out', out])
    return 1 if failed or code else 0


def clean_folders(options, name: str, tasks: list, runs_dir: pathlib.Path) -> bool:
    """Give the sessions to run clean folders (--resume); False, with the reasons, if refused.

    Without --resume a folder of an earlier sweep of ``name`` is refused: its sessions would
    mix with the new ones.
    """
    earlier = earlier_files(tasks)
    if earlier and not options.resume:
        for session_id, used in earlier.items():
            print(f'[experiment] {name}: session {session_id} holds files of an earlier run '
                  f'({"; ".join(used)})', file=sys.stderr)
        print(f'[experiment] {name} was run before: --resume continues it (finished sessions '
              'kept, the others run again in clean folders), or give another --name',
              file=sys.stderr)
        return False
    for line in set_aside(tasks, runs_dir) if earlier else []:
        print(f'[experiment] run again in a clean folder; the earlier files kept: {line}',
              flush=True)
    return True


def interrupt_on_signals() -> None:
    """Turn SIGINT and SIGTERM into KeyboardInterrupt (also when started with SIGINT ignored)."""
    def interrupt(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGINT, interrupt)    # nohup & starts with SIGINT ignored
    signal.signal(signal.SIGTERM, interrupt)


def announce(options, name, planned, executor, bags_dir, reused, tasks) -> None:
    """Print what the sweep runs, where, and (resumed) what earlier runs already did."""
    profiles = ', '.join(f'{profile or "default"}: {seeds} seeds'
                         for profile, seeds in options.profile_seeds.items())
    print(f'[experiment] {name}: {len(planned)} sessions ({len(options.cases)} cases; '
          f'{profiles}), learning configuration {options.learning}, engine '
          f'{options.engine}, on {executor.describe()}; bags in {bags_dir}', flush=True)
    if options.resume:
        versions = sorted({record['version'] for _, record in reused})
        print(f'[experiment] resuming: {len(reused)} of {len(planned)} sessions finished by '
              f'earlier runs of the folder ({", ".join(versions) or "none"}), {len(tasks)} '
              'to run', flush=True)


def manifest(options, planned, tasks, reused, outcomes, runs, description,
             uncommitted) -> dict:
    """Return the sweep's manifest: its runs, tasks and outcomes (the reused ones marked)."""
    this_run = runs[-1]
    record = {'command': this_run['command'],
              'engine': options.engine, 'executor': description, 'sessions': len(planned),
              'learning': options.learning,
              'failed': sorted(outcome['session_id'] for outcome in outcomes
                               if outcome['exit_code'] not in (0, None)),
              'skipped': sorted(outcome['session_id'] for outcome in outcomes
                                if outcome['exit_code'] is None),
              # the sum over the runs of the folder when resumed (each run's own in 'runs')
              'wall_seconds': sum(run.get('wall_seconds', 0.0) for run in runs),
              'started': runs[0].get('started', this_run['started']),
              'host_cpus': os.cpu_count(), 'version': this_run['version'],
              'uncommitted': uncommitted, 'runs': runs,
              'tasks': [asdict(task) for task in tasks] + [kept['task'] for _, kept in reused],
              'outcomes': sorted(outcomes + [dict(kept['outcome'], reused=True,
                                                  version=kept['version'])
                                             for _, kept in reused],
                                 key=lambda outcome: outcome['session_id'])}
    record['cpu_seconds'] = sum(outcome.get('cpu_seconds', 0.0) for outcome in outcomes) \
        + sum(kept['outcome'].get('cpu_seconds', 0.0) for _, kept in reused)
    return record


def _uncommitted_sources() -> list:
    """Return the source files that differ from the commit (run from a checkout), else [].

    The sessions run the code as it is on disk: the record says when that is not a commit.
    """
    try:
        status = subprocess.run(['git', 'status', '--porcelain', '--', 'src', 'params'],
                                capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.TimeoutExpired):
        return []
    return [line[3:] for line in status.stdout.splitlines()
            if line[:2].strip() and not line.startswith('??')] if status.returncode == 0 else []


def _version() -> str:
    return package_version()


if __name__ == '__main__':
    sys.exit(main())
