"""The experiment runner: a sweep on a real two-node Ray cluster equals the local pool's.

The local sweep runs in two parts, the second with ``--resume`` (it keeps the first's session
and runs only the other), which also tests resuming with real sessions.

The cluster is a head and a second node, each a ``ray start --block`` process of its own on
this machine with one CPU, in a private temporary directory; both are stopped (their process
groups, nothing else) in the teardown. Sessions: the in-process engine, 1 training and 1
evaluation episode of 4 s (tiny, so the test stays well under a minute).
"""

import json
import os
import signal
import socket
import subprocess
import tempfile
import threading
import time

from hrc_bringup import cli, experiment
from hrc_common.executables import executable_path
import pytest

from hrc_bag.report import load_records

# A private cluster on loopback: no usage reports, and no token authentication (Ray 2.60
# enables it on a head that finds ~/.ray/auth_token, while clients default to 'disabled').
RAY_ENV = dict(os.environ, RAY_USAGE_STATS_ENABLED='0', RAY_AUTH_MODE='disabled')
TINY = ['--cases', '1', '2', '--seeds', '1', '--episodes', '1', '--eval-episodes', '1',
        '--set', 'sim.episode_duration=4.0', '--no-report']


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        return probe.getsockname()[1]


def _ray(*args, log, env) -> subprocess.Popen:
    return subprocess.Popen(['ray', 'start', '--block', '--num-cpus=1', '--disable-usage-stats',
                             '--node-ip-address=127.0.0.1', *args], env=env, stdout=log,
                            stderr=subprocess.STDOUT, start_new_session=True)


def _stop(process: subprocess.Popen) -> None:
    """Stop a ``ray start --block`` process group (raylet, GCS, workers it started)."""
    try:
        os.killpg(process.pid, signal.SIGTERM)
        process.wait(timeout=5)
    except subprocess.TimeoutExpired:
        pass
    except ProcessLookupError:
        return
    try:
        os.killpg(process.pid, signal.SIGKILL)   # what SIGTERM left of this group only
    except ProcessLookupError:
        pass
    process.wait(timeout=10)


class LocalCluster:
    """A Ray cluster of two nodes (one CPU each) on this machine, started in the background."""

    def __init__(self):
        port = _free_port()
        self.temp_dir = tempfile.mkdtemp(prefix='hrcray', dir='/tmp')  # short: socket paths
        self.env = RAY_ENV
        self.log = open(os.path.join(self.temp_dir, 'ray.log'), 'w')
        self.address = f'127.0.0.1:{port}'
        self.processes = [_ray('--head', f'--port={port}', '--include-dashboard=false',
                               f'--temp-dir={self.temp_dir}', log=self.log, env=self.env)]

    def _status(self):
        return subprocess.run(['ray', 'status', f'--address={self.address}'], env=self.env,
                              capture_output=True, text=True)

    def wait_ready(self, timeout: float = 120.0) -> str:
        """Start the second node once the head answers; return when both are up."""
        deadline = time.monotonic() + timeout
        while self._status().returncode != 0:
            assert time.monotonic() < deadline, open(self.log.name).read()[-2000:]
            time.sleep(0.5)
        if len(self.processes) == 1:
            self.processes.append(_ray(f'--address={self.address}', log=self.log,
                                       env=self.env))
        while '2.0 CPU' not in self._status().stdout:
            assert time.monotonic() < deadline, self._status().stdout
            time.sleep(0.5)
        return self.address

    def stop(self) -> None:
        """Stop both nodes (their process groups only)."""
        for process in reversed(self.processes):
            _stop(process)
        self.log.close()


@pytest.fixture
def ray_cluster():
    """Yield a LocalCluster being started (call wait_ready before using it)."""
    cluster = LocalCluster()
    try:
        yield cluster
    finally:
        cluster.stop()


def _run_experiment(tmp_path, name, *extra) -> dict:
    command = [str(executable_path('hrc_bringup', 'hrc')), 'experiment', *TINY, '--name', name,
               '--bags-dir', str(tmp_path / 'bags'), '--runs-dir', str(tmp_path / 'runs'),
               *extra]
    result = subprocess.run(command, capture_output=True, text=True, timeout=150, env=RAY_ENV)
    assert result.returncode == 0, result.stdout + result.stderr
    return json.loads((tmp_path / 'bags' / name / 'experiment.json').read_text())


def _episodes(folder) -> dict:
    return {session.session_id: session.episodes for session in load_records([folder],
                                                                               log=print)}


def _check_the_resumed_local_sweep(tmp_path, first, local, stamps) -> None:
    """Check the local sweep: case 1, then cases 1 and 2 with --resume; only case 2 ran again."""
    outcomes = {outcome['session_id']: outcome for outcome in local['outcomes']}
    assert sorted(outcomes) == ['case1-seed0', 'case2-seed0']
    assert outcomes['case1-seed0']['reused'] and not outcomes['case2-seed0'].get('reused')
    bag = tmp_path / 'bags' / 'local' / 'case1-seed0'
    assert {path.name: path.stat().st_mtime_ns for path in bag.iterdir()} == stamps
    assert [run['sessions_run'] for run in local['runs']] == [1, 1]
    assert local['wall_seconds'] == pytest.approx(first['wall_seconds']
                                                  + local['runs'][1]['wall_seconds'])
    # every finished session was journalled the moment it ended (an interrupted sweep resumes
    # from there)
    journal = (tmp_path / 'bags' / 'local' / 'sessions.jsonl').read_text().splitlines()
    assert [json.loads(line)['outcome']['session_id'] for line in journal] == [
        'case1-seed0', 'case2-seed0']


@pytest.mark.slow
def test_sweep_on_a_two_node_ray_cluster_equals_the_local_pool(tmp_path, ray_cluster):
    # while Ray starts: the local sweep in two runs, the second resuming the first (--resume)
    first = _run_experiment(tmp_path, 'local', '--parallel', '1', '--cases', '1')
    bag = tmp_path / 'bags' / 'local' / 'case1-seed0'
    stamps = {path.name: path.stat().st_mtime_ns for path in bag.iterdir()}
    local = _run_experiment(tmp_path, 'local', '--parallel', '2', '--resume')
    _check_the_resumed_local_sweep(tmp_path, first, local, stamps)
    on_ray = _run_experiment(tmp_path, 'ray', '--ray-address', ray_cluster.wait_ready())
    assert 'Ray cluster (2 nodes, 2 CPUs' in on_ray['executor']
    assert 'local process pool' in local['executor']
    # one session per node: each node declares one CPU and each session asks for one
    assert len({outcome['ray_node'] for outcome in on_ray['outcomes']}) == 2
    local_episodes = _episodes(tmp_path / 'bags' / 'local')
    ray_episodes = _episodes(tmp_path / 'bags' / 'ray')
    assert sorted(local_episodes) == ['case1-seed0', 'case2-seed0']
    assert ray_episodes == local_episodes       # every summary field of every episode
    assert all(len(episodes) == 2 for episodes in ray_episodes.values())


def test_bad_arguments_exit_2_with_every_reason(tmp_path, capsys):
    # In this process (the `hrc` command's own entry point): a process of its own would spend
    # seconds importing torch only to refuse the arguments; a traceback would fail the test.
    code = cli.main(['experiment', '--cases', '9', '--seeds', '0', '--ray', '--ray-address',
                     'auto', '--set', 'x', '--bags-dir', str(tmp_path)])
    stderr = capsys.readouterr().err
    assert code == 2
    for reason in ('case must be one of', '--seeds must be >= 1', '--ray starts a local',
                   'x'):
        assert reason in stderr
    assert 'Traceback' not in stderr


class _Stop(Exception):
    pass


def test_a_signal_handed_to_another_thread_stops_the_sweep_at_once():
    """Ctrl-C or SIGTERM may reach any thread of the sweep: the main thread must still react.

    Python runs handlers in the main thread only; here the signal goes to a helper thread
    while the main thread waits for a 20 s task: the sweep must stop within seconds, not when
    the task ends (before the fix it waited for the task).
    """
    def stop(signum, frame):
        raise _Stop

    previous = signal.signal(signal.SIGUSR1, stop)
    pool = experiment.LocalPool(1)
    try:
        def send():
            time.sleep(1.0)
            signal.pthread_kill(threading.get_ident(), signal.SIGUSR1)
        threading.Thread(target=send, daemon=True).start()
        started = time.monotonic()
        with pytest.raises(_Stop):
            pool.run([20.0], lambda outcome: None, function=time.sleep)
        # within seconds (1 s, then a few wake periods), well before the 20 s task would end;
        # half the task leaves a busy machine its slowness
        assert time.monotonic() - started < 10.0
    finally:
        pool.close(abort=True)
        signal.signal(signal.SIGUSR1, previous)


def _echo_or_die(task: str) -> str:
    """Return the task's name, or kill this worker (SIGKILL) for 'die' (a sweep task)."""
    if task == 'die':
        os.kill(os.getpid(), signal.SIGKILL)
    return task


@pytest.mark.slow
def test_a_killed_ray_worker_loses_its_session_only_and_the_sweep_ends(ray_cluster,
                                                                      monkeypatch):
    """On a real local Ray cluster: the task whose worker is SIGKILLed is reported lost.

    Before, the driver died with a WorkerCrashedError traceback and lost the other sessions.
    """
    def echo_or_die(task):      # nested: Ray ships it to the workers by value
        import os  # lazy: runs on a Ray worker
        import signal  # lazy: as above
        if task == 'die':
            os.kill(os.getpid(), signal.SIGKILL)
        return task

    for name in ('RAY_USAGE_STATS_ENABLED', 'RAY_AUTH_MODE'):
        monkeypatch.setenv(name, RAY_ENV[name])
    executor = experiment.RayExecutor(ray_cluster.wait_ready(), 1.0, function=echo_or_die,
                                      lost=lambda task, how, seconds: f'{task}: {how}')
    outcomes = []
    try:
        executor.run(['a', 'die', 'b', 'c'], outcomes.append)
    finally:
        executor.close()
    assert sorted(outcome for outcome in outcomes if not outcome.startswith('die')) == [
        'a', 'b', 'c'], outcomes
    lost = [outcome for outcome in outcomes if outcome.startswith('die')]
    assert len(lost) == 1 and 'its Ray worker died (' in lost[0], outcomes


def test_a_killed_worker_loses_its_session_only_and_the_sweep_ends():
    """A SIGKILLed worker hung multiprocessing.Pool for ever; now its task alone is lost."""
    outcomes = []
    pool = experiment.LocalPool(2, lost=lambda task, how, seconds: f'{task}: {how}')
    sweep = threading.Thread(target=pool.run, daemon=True,
                             args=(['a', 'die', 'b', 'c'], outcomes.append, _echo_or_die))
    sweep.start()
    sweep.join(timeout=180)     # spawned workers take seconds each on a busy machine
    try:
        assert not sweep.is_alive(), f'the sweep hangs; outcomes so far: {outcomes}'
    finally:
        pool.close(abort=True)
    assert sorted(outcomes) == [
        'a', 'b', 'c', 'die: its worker process died (killed by SIGKILL)']
