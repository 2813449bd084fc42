"""A write that fails never reads as a success: exit 1 with the reason, never 0, never 2.

The final checkpoint stands in for any write of a session (a full disk, a folder not
writable): here its path is a folder, so the rename onto it fails (EISDIR) for root too.
Before, the graph's agent logged the error and the session exited 0; the in-process engine
exited 2, the code for bad parameters.
"""

import subprocess

import pytest

from hrc_agent_node.checkpoint import remove_stale_temporaries
from hrc_common.executables import executable_path

SHORT = ['--case', '2', '--episodes', '1', '--eval-episodes', '1', '--session-id', 's',
         '--runs-dir', 'runs', '--bags-dir', 'bags']


def run_session(tmp_path, *extra):
    (tmp_path / 'runs' / 'checkpoints' / 's' / 'final.pt').mkdir(parents=True)
    return subprocess.run([str(executable_path('hrc_bringup', 'hrc')), 'session', *SHORT,
                           *extra], cwd=tmp_path, capture_output=True, text=True, timeout=600)


def test_the_in_process_engine_exits_1_with_the_reason(tmp_path):
    result = run_session(tmp_path, '--engine', 'inprocess')
    assert result.returncode == 1, result.stdout + result.stderr
    assert result.stderr.strip().endswith('runs/checkpoints/s/final.pt: Is a directory (EISDIR)')
    assert 'Traceback' not in result.stderr


@pytest.mark.slow
def test_the_graph_exits_1_with_the_reason_and_the_resume_hint(tmp_path, ros_domain_id):
    result = run_session(tmp_path, '--mode', 'lockstep', '--domain-id', str(ros_domain_id))
    printed = result.stdout + result.stderr
    assert result.returncode == 1, printed
    assert 'final.pt not written: ' in printed and 'Is a directory (EISDIR)' in printed
    assert '--resume-from runs/checkpoints/s/latest.pt' in printed   # what was kept


def test_the_temporaries_of_a_killed_checkpoint_write_are_removed(tmp_path):
    for name in ('.latest.pt.a1b2.tmp', '.final.pt.c3d4.tmp', 'latest.pt', '.other.tmp'):
        (tmp_path / name).write_bytes(b'x')
    assert remove_stale_temporaries(tmp_path) == ['.final.pt.c3d4.tmp', '.latest.pt.a1b2.tmp']
    assert sorted(path.name for path in tmp_path.iterdir()) == ['.other.tmp', 'latest.pt']
    assert remove_stale_temporaries(tmp_path / 'missing') == []


def test_session_files_that_cannot_be_written_exit_1_before_any_node(tmp_path):
    """A full runs folder at the start ended in an OSError traceback."""
    (tmp_path / 'runs' / 's' / 'parameters.yaml').mkdir(parents=True)
    result = subprocess.run([str(executable_path('hrc_bringup', 'hrc')), 'session', *SHORT],
                            cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert result.returncode == 1, result.stdout + result.stderr
    assert result.stderr.strip() == ('session: cannot write the session files: '
                                     'runs/s/parameters.yaml: Is a directory (EISDIR)')
    assert not (tmp_path / 'bags').exists()
