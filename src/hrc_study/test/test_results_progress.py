"""The time left of `hrc results`, as plain lines when piped.

One step a session, then one for the tables, findings and figures. The clock is a test clock
(10 s a reading): the same lines on every run; stderr under pytest's capture is not a
terminal, as when the output is piped.
"""

import functools
import pathlib

from hrc_testing.bag_traffic import record_in_process, strategy_plan
from hrc_common.time_left import TimeLeft

from hrc_bag.report import figures
from hrc_study import results_cli, results_doc


class TickingClock:
    """A clock that advances 10 s at every reading."""

    def __init__(self):
        self.now = 0.0

    def __call__(self) -> float:
        self.now += 10.0
        return self.now


def test_results_shows_each_session_and_the_report_with_the_time_left(tmp_path, capsys,
                                                                        monkeypatch):
    plan = strategy_plan('learn_together', 2, 0, 1)
    for seed in (0, 1):
        record_in_process(tmp_path / 'bags', f'case5-seed{seed}', 5, 'learn_together', seed,
                          plan, steps=4)
    (tmp_path / 'bags' / 'notes').mkdir()        # not a session folder: not a step
    # the figures (seconds of matplotlib; drawn and checked in test_findings_chooser) are
    # left empty here
    for module, name in ((figures, 'figure_training'), (figures, 'figure_actions'),
                         (figures, 'figure_three_factor'), (results_doc, 'figure_convergence')):
        monkeypatch.setattr(module, name, lambda *args, **_: pathlib.Path(args[2]).touch())
    monkeypatch.setattr(results_cli, 'TimeLeft', functools.partial(TimeLeft,
                                                                   clock=TickingClock()))
    out = tmp_path / 'out'
    code = results_cli.main([str(tmp_path / 'bags'), '--out', str(out)])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert [line for line in printed.err.splitlines() if line.endswith(']')] == [
        'hrc_results: read case5-seed0 (1 session with episode summaries) '
        '[1/3 steps, 10 s, about 20 s left]',
        'hrc_results: read case5-seed1 (1 session with episode summaries) '
        '[2/3 steps, 20 s, about 10 s left]',
        f'hrc_results: wrote the tables, findings and figures to {out} [3/3 steps, 30 s, done]']
    assert (out / 'results.md').is_file()


def test_results_names_every_unreadable_session_at_once(tmp_path, capsys):
    for name in ('broken1', 'broken2'):
        session = tmp_path / 'bags' / name
        session.mkdir(parents=True)
        (session / f'{name}_episode0001.mcap').write_text('not an MCAP file')
    assert results_cli.main([str(tmp_path / 'bags'), '--out', str(tmp_path / 'out')]) == 1
    error = capsys.readouterr().err
    assert 'broken1_episode0001.mcap' in error and 'broken2_episode0001.mcap' in error
    assert 'Traceback' not in error
