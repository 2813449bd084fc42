"""scripts/rerun_study.py writes the results pages only after every learner's sessions ran.

Pages written into the work tree between the PPO and the SAC arm made the SAC sessions record
a "-dirty" version, so `--resume` of the SAC arm refused to keep them (found on 2026-12-02: 91
finished SAC sessions would have run again). The experiment, the spot check and hrc_results are
replaced by recorders here: the order of the calls is what is tested.
"""

import importlib.util
import pathlib

SCRIPT = pathlib.Path(__file__).resolve().parents[1] / 'scripts' / 'rerun_study.py'


def load_script():
    spec = importlib.util.spec_from_file_location('rerun_study_under_test', SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_learner_runs_before_any_page_is_written(tmp_path, monkeypatch):
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
    code = script.main(['--learners', 'ppo', 'sac', '--cases', '2', '--seeds', '1',
                        '--control-seeds', '0', '--spot-check', '--out', str(tmp_path),
                        '--bags-dir', str(tmp_path / 'bags'), '--runs-dir',
                        str(tmp_path / 'runs')])
    assert code == 0
    assert [kind for kind, _ in calls] == ['run', 'check', 'run', 'check', 'pages', 'pages'], calls
    assert calls[-2:] == [('pages', str(tmp_path)), ('pages', str(tmp_path / 'sac'))]
