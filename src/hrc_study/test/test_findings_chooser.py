"""Findings, measures and the strategy chooser on seeded synthetic sessions."""

import math

import pytest

from hrc_study.chooser import choose, parse_priorities
from hrc_study.findings import evaluate_findings
from hrc_study.sessions import final_block_start, measures
from hrc_study.statistics import holm

from hrc_study.synthetic import make_session, paper_like


def test_measures_count_judging_evaluations_as_training():
    session = make_session(2, 0, 0.2, episodes=20, converged=True, human_from=10,
                           evaluation_every=5, final_evaluations=3)
    values = measures(session)
    assert final_block_start(session) == 20
    assert values['total_episodes'] == 20            # 4 judging evaluations included
    assert values['human_involved_episodes'] == 10
    assert values['converged'] is True
    assert values['evaluation_episodes'] == 3
    assert values['total_error'] == pytest.approx(0.2, rel=0.03)   # final block only


def test_convergence_of_an_earlier_step_does_not_count():
    session = make_session(1, 0, 0.2, episodes=30, converged=False, human_from=10)
    session.episodes[5] = session.episodes[5].__class__(
        **{**session.episodes[5].__dict__, 'converged': True})   # step 0 converged only
    assert measures(session)['converged'] is False


def test_findings_hold_on_paper_like_data_and_are_holm_adjusted():
    findings = evaluate_findings(paper_like() + paper_like(profile='symmetric', seed=1))
    by_key = {finding.key: finding for finding in findings}
    assert set(by_key) == {'a', 'b', 'c', 'd', 'e', "e'"}
    for finding in findings:
        assert finding.verdict == 'holds', (finding.key, finding.reason)
    raw = [finding.p_value for finding in findings]
    assert [finding.p_holm for finding in findings] == pytest.approx(holm(raw))
    # the intersection-union p is the largest component p
    assert by_key['a'].p_value == max(component.result.p_value
                                      for component in by_key['a'].components)


def test_reversed_data_refute_a_and_e():
    findings = {finding.key: finding for finding in evaluate_findings(paper_like(flip=True))}
    assert findings['a'].verdict == 'does not hold'
    assert findings['e'].verdict == 'does not hold'
    assert 'other way' in findings['e'].reason


def test_equal_cases_are_inconclusive_and_missing_cases_are_named():
    sessions = [make_session(case_id, seed, 0.5 + 0.01 * seed, 100, True, human_from=0)
                for case_id in range(1, 7) for seed in range(4)]
    findings = {finding.key: finding for finding in evaluate_findings(sessions)}
    assert findings['a'].verdict == 'inconclusive'
    assert 'not significant' in findings['a'].reason
    few = [session for session in sessions if session.case_id != 3]
    findings = {finding.key: finding for finding in evaluate_findings(few)}
    assert findings['c'].verdict == 'inconclusive' and '[3]' in findings['c'].reason


def test_chooser_follows_the_weights_and_flags_unseparated_strategies():
    sessions = paper_like(seeds=6)
    performance = choose(sessions, parse_priorities('performance=1'), resamples=300)
    assert performance.ranking[0].strategy == 'responsibility_guided'
    assert performance.separated
    speed = choose(sessions, parse_priorities('time=1'), resamples=300)
    assert speed.ranking[0].strategy == 'level_guided'
    assert 'ranks first' in speed.explanation[0]
    same = [make_session(case_id, seed, 0.5 * (1 + 0.2 * ((seed * 7 + case_id) % 5)), 100,
                         True, human_from=0)
            for case_id in range(1, 7) for seed in range(6)]
    tie = choose(same, parse_priorities('balanced'), resamples=300)
    assert not tie.separated
    assert any('does NOT separate' in sentence for sentence in tie.explanation)
    interval = performance.ranking[0].factors['performance']
    assert interval.low <= interval.estimate <= interval.high


def test_priorities_are_checked_with_every_reason():
    assert parse_priorities('human=2, time=1') == {'performance': 0.0, 'human': 2.0,
                                                   'time': 1.0}
    with pytest.raises(ValueError) as error:
        parse_priorities('speed=1,human=x,time=-1')
    message = str(error.value)
    assert 'speed' in message and "'x'" in message and '>= 0' in message
    with pytest.raises(ValueError, match='> 0'):
        parse_priorities('human=0')
    assert math.isclose(sum(parse_priorities('least human time').values()), 5)


def test_results_document_carries_the_computed_numbers(tmp_path):
    from hrc_study.results_doc import cell, column_interval, write_results
    from hrc_study.statistics import kaplan_meier

    sessions = paper_like(seeds=4) + paper_like(seeds=3, profile='paper_symmetric', seed=2)
    outcomes = [{'profile': 'paper', 'case': case, 'seed': seed, 'exit_code': 0,
                 'finished_after': 100.0 + seed * 30 + case} for case in range(1, 7)
                for seed in range(10)]
    experiment = {'command': 'experiment --seeds 4', 'engine': 'inprocess', 'sessions': 61,
                  'wall_seconds': 420.0, 'executor': 'local process pool (2 workers)',
                  'outcomes': outcomes + [{'profile': 'paper', 'case': 1, 'seed': 10,
                                           'exit_code': None}], 'skipped': ['case1-seed10']}
    result = write_results(sessions, tmp_path, 'hrc_results x', experiment,
                           parse_priorities('human=1'), note='A note.', resamples=100)
    text = (tmp_path / 'results.md').read_text()
    case2 = [measures(s) for s in sessions if s.case_id == 2 and s.profile == 'paper']
    assert cell(column_interval([v['total_error'] for v in case2], 'total_error'), 3) in text
    # the physical effort of case 2's robot (rotation): N*m squared
    assert cell(column_interval([v['robot_effort_physical'] for v in case2],
                                'robot_effort_physical'), 4) + ' (N*m)^2' in text
    case4 = [measures(s) for s in sessions if s.case_id == 4 and s.profile == 'paper']
    km = kaplan_meier([v['total_episodes'] for v in case4], [v['converged'] for v in case4])
    assert f'| 4 | 4/4 | {km.describe()} |' in text
    assert "| (e') |" in text and 'paper_symmetric' in text and 'A note.' in text
    assert '60 of 61 planned sessions finished in 7.0 min wall' in text
    assert '1 not started (--stop-after)' in text and '**your priorities**' in text
    assert '| 6.3 min wall for the 60 sessions of profile paper' in text   # 376 s
    assert '| 5 | 0/4 | > 300 (not reached) |' in text
    for name in ('fig5_training.png', 'fig6_actions.png', 'fig7_three_factor.png',
                 'convergence.png', 'sessions.csv'):
        assert (tmp_path / 'results' / name).stat().st_size > 0
    assert [target for target, _, met in result['targets'] if met is False] == [
        'every case converges in >= 8/10 seeds']


def test_a_file_that_is_not_mcap_is_named_without_a_traceback(tmp_path, capsys):
    from hrc_study.results_cli import main

    session = tmp_path / 'bags' / 'broken'
    session.mkdir(parents=True)
    (session / 'broken_ep0000.mcap').write_text('not an MCAP file')
    assert main([str(tmp_path / 'bags'), '--out', str(tmp_path / 'out')]) == 1
    assert 'is not an MCAP file' in capsys.readouterr().err


def test_student_t_setting_reproduces_the_tables_before_issue_23(tmp_path):
    from hrc_study.results_doc import cell, table2_markdown, UNITS_CAVEAT, write_results
    from hrc_study.statistics import mean_interval

    sessions = paper_like(seeds=4)
    write_results(sessions, tmp_path, 'hrc_results x', resamples=50, intervals='student-t')
    text = (tmp_path / 'results.md').read_text()
    case5 = [measures(s) for s in sessions if s.case_id == 5]
    old_cell = cell(mean_interval(v['total_error'] for v in case5), 3)
    assert old_cell in text and 'Intervals: Student t' in text
    assert old_cell not in table2_markdown({5: case5})     # the default (BCa) differs
    assert UNITS_CAVEAT in text     # beside the comparison with the paper
