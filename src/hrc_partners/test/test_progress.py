"""The time left of `hrc partners crossplay` and `hrc partners clone`, as plain lines when piped.

The clock is a test clock (10 s a reading), so the lines are the same on every run; stderr
under pytest's capture is not a terminal, as when the output is piped.
"""

import functools

from hrc_common.time_left import duration, TimeLeft

from hrc_partners import clone_cli, crossplay, crossplay_cli, synthetic


class TickingClock:
    """A clock that advances ``step`` seconds at every reading."""

    def __init__(self, step: float = 10.0):
        self.now, self.step = 0.0, step

    def __call__(self) -> float:
        self.now += self.step
        return self.now


def test_crossplay_shows_each_cell_with_the_time_left(tmp_path, capsys, monkeypatch):
    # The cells' evaluation is stubbed (a real one trains and runs sessions: the slow test of
    # test_crossplay.py); what is tested is the count of cells, the training partner's column
    # included, and the line per cell.
    for name in ('a', 'b'):
        (tmp_path / f'{name}.pt').write_bytes(b'')
    (tmp_path / 'a.json').write_text('{"training_partner": "profile:paper"}')
    monkeypatch.setattr(crossplay, 'evaluate', lambda checkpoint, spec, seed, *rest:
                        0.25 + 0.125 * seed)
    monkeypatch.setattr(crossplay_cli, 'TimeLeft',
                        functools.partial(TimeLeft, clock=TickingClock()))
    code = crossplay_cli.main(['--agent', f'a={tmp_path / "a.pt"}', f'b={tmp_path / "b.pt"}',
                               '--partner', 'person:paper:7', '--seeds', '0', '1',
                               '--episodes', '1', '--out', str(tmp_path / 'out')])
    assert code == 0, capsys.readouterr().err
    assert capsys.readouterr().err.splitlines() == [
        # 2 agents x 2 columns (person:paper:7 and a's training partner profile:paper)
        'crossplay: a x person:paper:7: 0.2500 0.3750 [1/4 cells, 10 s, about 30 s left]',
        'crossplay: a x profile:paper: 0.2500 0.3750 [2/4 cells, 20 s, about 20 s left]',
        'crossplay: b x person:paper:7: 0.2500 0.3750 [3/4 cells, 30 s, about 10 s left]',
        'crossplay: b x profile:paper: 0.2500 0.3750 [4/4 cells, 40 s, done]']


def test_crossplay_cell_count_is_what_run_matrix_evaluates(tmp_path):
    agents = [crossplay.Agent('a', 'a.pt', 'profile:paper'),
              crossplay.Agent('b', 'b.pt', 'population:paper'),
              crossplay.Agent('c', 'c.pt', 'person:paper:7')]
    assert crossplay_cli.cell_count(agents, ['person:paper:7']) == 3 * 3
    assert crossplay_cli.cell_count(agents[2:], ['person:paper:7']) == 1


def test_clone_shows_the_sessions_read_and_the_epochs_with_the_time_left(tmp_path, capsys,
                                                                           monkeypatch):
    profiles = synthetic.fast_and_slow(tmp_path / 'people.yaml')
    folders = synthetic.record_sessions(tmp_path / 'bags', tmp_path / 'runs', profiles,
                                        ['fast'], [0, 1], episodes=1, seconds=4.0)
    capsys.readouterr()
    monkeypatch.setattr(clone_cli, 'TimeLeft', functools.partial(TimeLeft, clock=TickingClock()))
    code = clone_cli.main(folders + ['--out', str(tmp_path / 'fast.pt'), '--epochs', '20',
                                     '--targets', 'command'])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    lines = [line for line in printed.err.splitlines() if '[' in line]
    assert lines == [
        'clone_human: read fast-seed0 (20 driven steps) [1/2 sessions, 10 s, about 10 s left]',
        'clone_human: read fast-seed1 (20 driven steps) [2/2 sessions, 20 s, done]',
        # a line every tenth of the 20 epochs when piped
        # (10 s of the test clock between two lines: 5 s an epoch, 5 s x the epochs to go)
        *[f'clone_human: training [{done}/20 epochs, {duration(5 * done)}'
          + (f', about {duration(5 * (20 - done))} left]' if done < 20 else ', done]')
          for done in range(2, 21, 2)]]
    assert lines[5] == ('clone_human: training [8/20 epochs, 40 s, about 1 min 00 s left]')
