"""A session id names one session: a second run with it is refused, a sweep run again is clean.

A second ``hrc session --session-id X`` used to file its episodes as attempts of the first in
``bags/X`` and overwrite its ``final.pt``; ``hrc experiment`` run again with a name it had run
(or ``--resume`` after a killed session) put the new sessions' files beside the old ones.
"""

import os
import pathlib
import queue
import signal
import subprocess
import threading
import types

from hrc_common.executables import executable_path
from hrc_common.session_plan import SessionSettings
import pytest

from hrc_bringup.experiment_resume import earlier_files, set_aside


def hrc(*arguments, cwd):
    return subprocess.run([str(executable_path('hrc_bringup', 'hrc')), *arguments], cwd=cwd,
                          capture_output=True, text=True, timeout=300)


def test_a_second_session_with_an_id_in_use_is_refused_and_writes_nothing(tmp_path):
    bag = tmp_path / 'bags' / 'pilot'
    bag.mkdir(parents=True)
    (bag / 'pilot_episode0001.mcap').write_bytes(b'an earlier session')
    result = hrc('session', '--session-id', 'pilot', '--bags-dir', 'bags', '--runs-dir', 'runs',
                 cwd=tmp_path)
    assert result.returncode == 2, result.stdout + result.stderr
    assert result.stderr.strip() == (
        'session: --session-id pilot: in use by another session (bags bags/pilot (1 file)): '
        'give another --session-id')
    assert not (tmp_path / 'runs').exists()
    assert [path.name for path in bag.iterdir()] == ['pilot_episode0001.mcap']


def test_an_experiment_run_again_under_its_name_is_refused_without_resume(tmp_path):
    earlier = tmp_path / 'bags' / 'sweep' / 'case2-seed0'
    earlier.mkdir(parents=True)
    (earlier / 'case2-seed0_episode0001.mcap').write_bytes(b'an earlier sweep')
    result = hrc('experiment', '--name', 'sweep', '--cases', '2', '--seeds', '1', '--no-report',
                 '--bags-dir', 'bags', '--runs-dir', 'runs', cwd=tmp_path)
    assert result.returncode == 2, result.stdout + result.stderr
    assert ('[experiment] sweep: session case2-seed0 holds files of an earlier run (bags '
            f'{earlier} (1 file))') in result.stderr
    assert '--resume continues it' in result.stderr and 'Traceback' not in result.stderr
    assert (earlier / 'case2-seed0_episode0001.mcap').read_bytes() == b'an earlier sweep'


def test_a_session_run_again_by_resume_starts_clean_and_keeps_the_earlier_files(tmp_path):
    settings = SessionSettings(session_id='case2-seed0', bags_dir=str(tmp_path / 'bags'),
                               runs_dir=str(tmp_path / 'runs' / 'case2-seed0'))
    task = types.SimpleNamespace(session_id='case2-seed0', settings=settings)
    killed = {'bags': pathlib.Path(settings.bags_dir) / 'case2-seed0' / 'x_episode0001.mcap',
              'run': pathlib.Path(settings.runs_dir) / 'case2-seed0' / 'session.yaml'}
    for path in killed.values():
        path.parent.mkdir(parents=True)
        path.write_text('the killed run')
    assert list(earlier_files([task])) == ['case2-seed0']
    for attempt in (1, 2):
        moved = set_aside([task], tmp_path / 'runs')
        assert len(moved) == 2 and earlier_files([task]) == {}
        kept = tmp_path / 'runs' / 'earlier-runs' / f'case2-seed0-{attempt}'
        assert (kept / 'bags' / 'x_episode0001.mcap').read_text() == 'the killed run'
        assert (kept / 'run-folder' / 'session.yaml').read_text() == 'the killed run'
        for path in killed.values():            # the next attempt's leftovers
            path.parent.mkdir(parents=True)
            path.write_text('the killed run')


@pytest.mark.slow
def test_a_session_on_the_domain_of_a_running_one_is_refused(tmp_path, ros_domain_id):
    """Two sessions on one domain took each other's messages (one agent died of the other's)."""
    command = [str(executable_path('hrc_bringup', 'hrc')), 'session', '--domain-id',
               str(ros_domain_id), '--bags-dir', 'bags', '--runs-dir', 'runs']
    first = subprocess.Popen([*command, '--session-id', 'first', '--episodes', '200'],
                             cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             text=True, start_new_session=True)
    lines = queue.Queue()
    threading.Thread(target=lambda: [lines.put(line) for line in first.stdout],
                     daemon=True).start()
    try:
        seen = []
        while not any(line.startswith('[session] first: case 2') for line in seen):
            seen.append(lines.get(timeout=120))     # the first session is up
        second = hrc('session', '--domain-id', str(ros_domain_id), '--session-id', 'second',
                     '--bags-dir', 'bags', '--runs-dir', 'runs', cwd=tmp_path)
        assert second.returncode == 2, second.stdout + second.stderr
        assert second.stderr.strip() == (
            f'session: ROS_DOMAIN_ID {ros_domain_id} is in use by session first (pid '
            f"{first.pid}) on this machine: its nodes would take this session's messages; "
            'give --domain-id with another id (0..101)')
        assert not (tmp_path / 'runs' / 'second').exists()
        assert first.poll() is None                 # the first one goes on
    finally:
        os.killpg(first.pid, signal.SIGINT)
        try:
            first.wait(timeout=120)
        except subprocess.TimeoutExpired:
            os.killpg(first.pid, signal.SIGKILL)
            first.wait()
