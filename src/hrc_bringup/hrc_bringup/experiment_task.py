"""One session of an experiment sweep, run on a worker: :func:`run_task` of a :class:`SessionTask`.

A task runs the session with the chosen engine (``inprocess``: ``hrc_engine.run_session`` in
the worker process; ``graph``: the ``hrc session`` runner on a ROS domain reserved on the
worker's machine), pre-trains cases 7 and 8 with their simulated population first, and returns
its outcome as plain data (with the session's bag folder packed when the driver has no shared
filesystem: :func:`pack_folder` / :func:`unpack_folder`). The sweep itself (executors, command
line, report) is ``hrc_bringup.experiment``.
"""

from dataclasses import dataclass, replace
import io
import os
import pathlib
import resource
import shutil
import socket
import subprocess
import sys
import tarfile
import tempfile
import time

from hrc_common.contract import make_session_id
from hrc_common.domains import DomainReservation
from hrc_common.executables import executable_path
from hrc_common.session_plan import override_arguments, SessionSettings
from hrc_engine.engine import compose_parameters, EngineConfig, run_session
from hrc_partners.partners_first import prepare_person_session


@dataclass(frozen=True)
class SessionTask:
    """One session of the sweep: everything a worker needs, as plain values (picklable).

    ``settings`` is the session (the one session configuration, as ``hrc session`` takes it):
    its ``bags_dir`` is ``<bags-dir>/<name>`` and its ``runs_dir`` ``<runs-dir>/<name>/<id>``,
    both absolute; the other fields are how the sweep runs it.
    """

    settings: SessionSettings
    engine: str                     # inprocess | graph
    params_dir: str                 # the parameter files, resolved on the driver
    pull_bags: bool                 # return the session folder packed (no shared filesystem)
    checkpoints: bool = False       # in-process: write the agent's checkpoints (resumable)
    not_after: float = 0.0          # epoch s: a task not started by then is skipped (0: none)

    @property
    def session_id(self) -> str:
        """Return the session's id (its bag and run folders' name)."""
        return self.settings.session_id

    @property
    def sweep_runs_dir(self) -> pathlib.Path:
        """Return the sweep's runs folder (each session's log lands there)."""
        return pathlib.Path(self.settings.runs_dir).parent


def session_id_of(case: int, seed: int, profile: str, profiles: list) -> str:
    """Return the session id: 'case2-seed0', with '-<profile>' when several profiles run."""
    base = make_session_id(case, seed, timestamped=False)
    return f'{base}-{profile}' if len(profiles) > 1 and profile else base


def task_outcome(task: SessionTask, exit_code=1, error: str = '') -> dict:
    """Return the outcome record of ``task`` as a worker starts it (a failure until it ends)."""
    settings = task.settings
    return {'session_id': settings.session_id, 'case': settings.case, 'seed': settings.seed,
            'profile': settings.human_profile, 'engine': task.engine,
            'host': socket.gethostname(), 'worker_pid': os.getpid(), 'exit_code': exit_code,
            'error': error}


def lost_outcome(task: SessionTask, how: str, seconds: float) -> dict:
    """Return the outcome of a task whose worker died before it answered (exit code 1)."""
    outcome = task_outcome(task, 1, f'session lost: {how}')
    outcome.update(host=socket.gethostname(), worker_pid=None, seconds=seconds)
    return outcome


def run_task(task: SessionTask) -> dict:
    """Run one session on this worker; return its outcome (never raises)."""
    started, cpu_started = time.monotonic(), _cpu_seconds()
    settings = task.settings
    outcome = task_outcome(task)
    if task.not_after and time.time() > task.not_after:
        outcome.update(exit_code=None, error='skipped: --stop-after passed', seconds=0.0)
        return outcome
    try:
        node = _ray_node_id()
        if node:
            outcome['ray_node'] = node
        bags_dir = pathlib.Path(tempfile.mkdtemp(prefix='hrc-bags-')) if task.pull_bags \
            else pathlib.Path(settings.bags_dir)
        runner = run_inprocess if task.engine == 'inprocess' else run_graph
        try:
            outcome['exit_code'], outcome['error'] = runner(task, bags_dir)
            if task.pull_bags:
                outcome['bag_archive'] = pack_folder(bags_dir / task.session_id)
        finally:
            if task.pull_bags:
                shutil.rmtree(bags_dir, ignore_errors=True)
    except Exception as error:   # a worker reports every failure back to the driver
        outcome['error'] = f'{type(error).__name__}: {error}'
    outcome['seconds'] = time.monotonic() - started
    # CPU time of this worker and its children (the graph's nodes) during the session: what
    # the session costs whatever else the machine runs
    outcome['cpu_seconds'] = _cpu_seconds() - cpu_started
    return outcome


def _cpu_seconds() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def _ray_node_id() -> str:
    if 'ray' not in sys.modules:
        return ''
    import ray  # lazy: optional heavy dependency (the --ray executor), loaded by then
    try:
        return ray.get_runtime_context().get_node_id() if ray.is_initialized() else ''
    except Exception:   # not inside a Ray worker
        return ''


def engine_config_of(task: SessionTask, bags_dir: pathlib.Path) -> EngineConfig:
    """Return the in-process engine's configuration of a task (its bags in ``bags_dir``)."""
    return EngineConfig(replace(task.settings, bags_dir=str(bags_dir)),
                        params_dir=task.params_dir, checkpoints=task.checkpoints)


def pretrain_partners_first(task: SessionTask, bags_dir: pathlib.Path):
    """Pre-train a partners-first task with its population; return the agent's new parameters.

    None for the other cases. The session's parameters are composed as the engine composes
    them (the graph's agent, sim and human parameters are the same), and the pre-training's
    files go to the session's run folder.
    """
    _, parameters = compose_parameters(engine_config_of(task, bags_dir))
    session_dir = pathlib.Path(task.settings.runs_dir) / task.session_id
    session_dir.mkdir(parents=True, exist_ok=True)
    return prepare_person_session(parameters, session_dir)


def run_inprocess(task: SessionTask, bags_dir: pathlib.Path) -> tuple:
    """Run the session with the in-process engine; return (exit code, error text)."""
    config = engine_config_of(task, bags_dir)
    start = pretrain_partners_first(task, bags_dir)
    if start is not None:
        config.settings.resume_from = start['resume_from']
        config.settings.training_episodes = start['max_training_episodes']
    run_session(config)
    return 0, ''


def graph_arguments(settings: SessionSettings, params_dir: str, domain_id: int) -> list:
    """Return the ``hrc session`` arguments that run ``settings`` as the graph (no report).

    ``hrc session`` parses them back into the same SessionSettings (a test checks it).
    """
    arguments = ['--case', str(settings.case), '--seed', str(settings.seed), '--session-id',
                 settings.session_id, '--bags-dir', settings.bags_dir, '--no-report',
                 '--runs-dir', settings.runs_dir, '--params-dir', params_dir,
                 '--domain-id', str(domain_id), '--learning', settings.learning]
    if settings.human_profile:
        arguments += ['--profile', settings.human_profile]
    if settings.resume_from:
        arguments += ['--resume-from', settings.resume_from]
    if settings.training_episodes > 0:
        arguments += ['--episodes', str(settings.training_episodes)]
    if settings.evaluation_episodes >= 0:
        arguments += ['--eval-episodes', str(settings.evaluation_episodes)]
    return arguments + override_arguments(settings.overrides)


def run_graph(task: SessionTask, bags_dir: pathlib.Path) -> tuple:
    """Run the session as the ROS graph on a domain reserved on this machine."""
    reservation = DomainReservation()
    try:
        settings = replace(task.settings, bags_dir=str(bags_dir))
        # partners first: the session starts from the pre-trained checkpoint, its budget on top
        start = pretrain_partners_first(task, bags_dir)
        if start is not None:
            settings.resume_from = start['resume_from']
            settings.training_episodes = start['max_training_episodes']
        command = [str(executable_path('hrc_bringup', 'hrc')), 'session',
                   *graph_arguments(settings, task.params_dir, reservation.domain_id)]
        task.sweep_runs_dir.mkdir(parents=True, exist_ok=True)
        with open(task.sweep_runs_dir / f'{task.session_id}.log', 'wb') as log:
            code = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT).returncode
    finally:
        reservation.release()
    return code, '' if code == 0 else f'session exited with {code}'


def pack_folder(folder: pathlib.Path) -> bytes:
    """Return ``folder`` as a gzipped tar (its name as the top entry)."""
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode='w:gz') as archive:
        archive.add(folder, arcname=folder.name)
    return buffer.getvalue()


def unpack_folder(data: bytes, target: pathlib.Path, expected: str) -> None:
    """Unpack a session archive into ``target`` (only members under ``expected``)."""
    with tarfile.open(fileobj=io.BytesIO(data), mode='r:gz') as archive:
        members = [member for member in archive.getmembers()
                   if member.name == expected or member.name.startswith(expected + '/')]
        archive.extractall(target, members=members, filter='data')
