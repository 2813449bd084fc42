"""What hrc writes where it runs stays out of git; the code beside it does not.

``hrc bag report`` writes ``report/`` and ``hrc study`` the subject registry, the session index
and the NASA-TLX answers under ``study/`` (personal data) in the folder it runs in: the
repository's root when run from a clone. The python package ``hrc_bag.report`` must not be
ignored with them.
"""

import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def ignored(path: str) -> bool:
    # --no-index: decided by .gitignore alone, whether the file exists or is tracked
    result = subprocess.run(['git', 'check-ignore', '--no-index', '-q', path], cwd=ROOT,
                            capture_output=True, text=True, timeout=30)
    assert result.returncode in (0, 1), result.stderr
    return result.returncode == 0


@pytest.mark.parametrize('path', ['study/subjects.yaml', 'study/index.yaml', 'study/tlx.yaml',
                                  'report/table2.md', 'results/results.md', 'runs/x/final.pt',
                                  'bags/s/s_episode0002.mcap'])
def test_what_a_session_writes_is_ignored(path):
    assert ignored(path)


@pytest.mark.parametrize('path', ['src/hrc_bag/hrc_bag/report/tables.py',
                                  'src/hrc_live/hrc_live/study.py', 'docs/results.md'])
def test_the_code_and_docs_are_not_ignored(path):
    assert not ignored(path)
