"""scripts/rerun_study.py writes the results pages only after every configuration's sessions ran.

Pages written into the work tree between the PPO and the SAC arm made the SAC sessions record
a "-dirty" version, so `--resume` of the SAC arm refused to keep them (found on 2026-12-02: 91
finished SAC sessions would have run again). The experiment, the spot check and hrc_results are
replaced by recorders here: the order of the calls is what is tested. Also: started without
the workspace's environment, the script says what to run (exit 2) instead of a traceback.
"""

import importlib.util
import pathlib

SCRIPT = pathlib.Path(__file__).resolve().parents[1] / 'scripts' / 'rerun_study.py'


def load_script():
    spec = importlib.util.spec_from_file_location('rerun_study_under_test', SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_configuration_runs_before_any_page_is_written(tmp_path, monkeypatch):
    script = load_script()
    calls = []
    monkeypatch.setattr(script, 'uncommitted', lambda: [])
    monkeypatch.setattr(script, 'commit', lambda: 'abc1234')
    monkeypatch.setattr(script, 'experiment',
                        lambda options, name, learner, extra: calls.append(('run', learner))
                        or 0)
    monkeypatch.setattr(script, 'spot_check',
                        lambda options, learner, folder: calls.append(('check', learner))
                        or [])

    class Finished:
        returncode = 0

    def fake_run(command, check=False):
        calls.append(('pages', command[command.index('--out') + 1]))
        return Finished()

    monkeypatch.setattr(script.subprocess, 'run', fake_run)
    code = script.main(['--learnings', 'ppo', 'sac', '--cases', '2', '--seeds', '1',
                        '--control-seeds', '0', '--spot-check', '--out', str(tmp_path),
                        '--bags-dir', str(tmp_path / 'bags'), '--runs-dir',
                        str(tmp_path / 'runs')])
    assert code == 0
    assert [kind for kind, _ in calls] == ['run', 'check', 'run', 'check', 'pages', 'pages'], calls
    # the default configuration (sac) writes --out itself, every other one --out/<name>
    assert calls[-2:] == [('pages', str(tmp_path / 'ppo')), ('pages', str(tmp_path))]


def test_started_without_the_workspace_it_says_what_to_run_and_exits_2():
    """Without scripts/env.sh the hrc packages are not importable: a sentence, no traceback."""
    import os
    import subprocess
    import sys

    environment = {name: value for name, value in os.environ.items()
                   if name not in ('PYTHONPATH', 'AMENT_PREFIX_PATH')}
    finished = subprocess.run([sys.executable, str(SCRIPT), '--help'], env=environment,
                              capture_output=True, text=True, timeout=60)
    assert finished.returncode == 2, finished
    assert 'Traceback' not in finished.stderr
    assert "No module named 'hrc_" in finished.stderr
    assert 'source scripts/env.sh' in finished.stderr
