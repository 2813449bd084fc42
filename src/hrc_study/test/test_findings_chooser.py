"""Findings, measures and the strategy chooser on seeded synthetic sessions."""

import math
import pathlib
import re

import pytest

from hrc_study.chooser import choose, parse_priorities
from hrc_study.findings import evaluate_findings
from hrc_bag.report.records import final_block_start, measures
from hrc_study.statistics import holm

from hrc_testing.study_records import make_session, paper_like


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
    from hrc_bag.report.intervals import cell, column_interval
    from hrc_study.results_doc import write_results
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
    human = kaplan_meier([v['human_involved_episodes'] for v in case4],
                         [v['converged'] for v in case4])
    # (b)'s measure, censored, by KM; the strict rule's floor (2 steps of T 1 + W 3)
    assert f'| {human.describe()} | 8 / 8 | 14 |' in text
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
    (session / 'broken_episode0001.mcap').write_text('not an MCAP file')
    assert main([str(tmp_path / 'bags'), '--out', str(tmp_path / 'out')]) == 1
    assert 'is not an MCAP file' in capsys.readouterr().err


def test_the_documents_table2_is_the_reports(tmp_path, monkeypatch):
    from hrc_bag.report import figures
    from hrc_study import results_doc
    from hrc_study.results_tables import UNITS_CAVEAT

    # The tables only: the figures (seconds of matplotlib; drawn and checked by the test
    # above) are left empty here.
    for module, name in ((figures, 'figure_training'), (figures, 'figure_actions'),
                         (figures, 'figure_three_factor'), (results_doc, 'figure_convergence')):
        monkeypatch.setattr(module, name, lambda *args, **_: pathlib.Path(args[2]).touch())
    sessions = paper_like(seeds=4)
    results_doc.write_results(sessions, tmp_path, 'hrc results x', resamples=50,
                              table_resamples=200)
    text = (tmp_path / 'results.md').read_text()
    report = (tmp_path / 'results' / 'table2.md').read_text()
    rows = [line for line in report.splitlines() if re.match(r'^\| \d \|', line)]
    assert len(rows) == 6              # one per case (no episode duration: no person's time)
    assert all(row in text for row in rows)
    assert 'Intervals: 95% BCa bootstrap' in text and UNITS_CAVEAT in text


# ---------------------------------------------------------------- the findings


def _sessions(spec, seeds=10, kinds=False):
    """Return sessions from {case: (total_error(seed), episodes, converged, human_from)}."""
    return [make_session(case_id, seed, error(seed), episodes, converged,
                         human_from=human_from, kinds=kinds)
            for case_id, (error, episodes, converged, human_from) in spec.items()
            for seed in range(seeds)]


def test_finding_b_treats_capped_human_counts_as_censored():
    # nobody converges: task first's human-involved count is 260 only because its
    # robot-alone step used 40 of the 300 episodes. Mann-Whitney (the old test) said "holds".
    spec = {case: ((lambda seed: 0.5 + 0.01 * seed), 300, False,
                   40 if case in (1, 2) else 0) for case in range(1, 7)}
    findings = {finding.key: finding for finding in evaluate_findings(_sessions(spec))}
    b = findings['b']
    assert [component.result.test.split(' (')[0] for component in b.components] == [
        'exact signed-rank by pair'] * 4
    assert b.p_value == 1.0 and b.verdict == 'inconclusive'
    assert 'no difference either way' in b.reason
    assert 'tied or undecided in 10 of 10 pairs' in b.reason


def test_finding_d_contrasts_case_5_with_cases_1_and_3():
    # cases 1, 3 and 5 all fail to converge and have the same error: the old test ("case 5
    # converges in fewer than half of its seeds") held; case 5 is not singled out.
    spec = {case: ((lambda seed, case=case: 0.5 + 0.01 * ((seed * 3 + case) % 7)),
                   300 if case in (1, 3, 5) else 100, case not in (1, 3, 5), 0)
            for case in range(1, 7)}
    findings = {finding.key: finding for finding in evaluate_findings(_sessions(spec))}
    d = findings['d']
    assert d.p_value > 0.5 and d.verdict != 'holds'
    assert '0/10 of case 5 converged' in d.effect
    # case 5 alone failing (1 and 3 converge) holds
    spec.update({case: (spec[case][0], 120, True, 0) for case in (1, 3)})
    findings = {finding.key: finding for finding in evaluate_findings(_sessions(spec))}
    assert findings['d'].verdict == 'holds', findings['d'].reason


def test_a_reversal_is_holm_corrected_within_the_finding():
    # case 1 is above case 3 in all 6 pairs (exact signed-rank reverse p = 1/64 = 0.0156, alone
    # significant); the other three comparisons of (a) are noise. Holm over the 4: 0.0625.
    from hrc_study.findings import CaseData, finding_a

    def noise(seed, case):
        return 0.02 * (((seed * 5 + case * 3) % 7) - 3)

    offset = {1: 0.3, 5: 0.3}          # case 5 level with case 1: only 1 vs 3 reverses
    spec = {case: ((lambda seed, case=case: 1.0 + 0.2 * seed + noise(seed, case)
                    + offset.get(case, 0.0)), 100, True, 0) for case in range(1, 7)}
    finding = finding_a(CaseData(_sessions(spec, seeds=6)), 'paper')
    first = finding.components[0]
    assert first.label == 'case 1 vs case 3'
    assert first.result.p_reverse == pytest.approx(1 / 64)
    assert finding.p_reverse == pytest.approx(4 / 64)
    assert 'case 1 vs case 3 goes the other way' in finding.reversal


def test_unpaired_sessions_fall_back_to_the_unpaired_tests():
    from hrc_study.findings import CaseData, compare_lower

    sessions = _sessions({1: ((lambda seed: 0.3 + 0.01 * seed), 100, True, 0),
                          3: ((lambda seed: 0.6 + 0.01 * seed), 100, True, 0)}, seeds=5)
    data = CaseData(sessions)
    assert data.paired('paper', 1, 3) == [(seed, -1) for seed in range(5)]
    assert compare_lower(data, 'paper', 1, 3, 'total_error').test.startswith('Wilcoxon')
    sessions[-1].seed = 9                       # case 3's last seed has no twin in case 1
    data = CaseData(sessions)
    assert data.paired('paper', 1, 3) is None
    assert compare_lower(data, 'paper', 1, 3, 'total_error').test.startswith('Mann-Whitney')


def test_fig5_keeps_every_seed_and_plots_judging_apart():
    from hrc_bag.report.curves import return_band, returns_of_kind

    # three seeds that stop after 10, 20, 30 episodes; every 5th is a judging episode
    # (return 100), the others return their index
    sessions = [make_session(2, seed, 0.2, episodes, True, evaluation_every=5, kinds=True)
                for seed, episodes in enumerate((10, 20, 30))]
    assert all(value != 100 for _, value in returns_of_kind(sessions[2], 'training'))
    assert [value for _, value in returns_of_kind(sessions[2], 'judging')] == [100.0] * 6
    band = return_band(sessions, 'training')
    assert band.stops == [10, 20, 30] and band.running[-1] == 1
    # at episode 30 the stopped seeds are carried at their last training return (8, 18):
    # median over all three is 18, not the survivor's 28; the band is their IQR
    assert band.median[-1] == 18.0
    assert (band.low[-1], band.high[-1]) == (13.0, 23.0)
    judging = return_band(sessions, 'judging')
    assert judging.median[-1] == 100.0 and math.isnan(judging.median[0])
    # old sessions (kinds unknown): no judging row, every non-evaluation episode is training
    old = [make_session(2, 0, 0.2, 10, True)]
    assert returns_of_kind(old[0], 'judging') == []


def test_an_inconclusive_finding_names_the_power_limit():
    # five seeds of the control profile, every pair in the claimed direction: the signed-rank
    # p cannot go below 2^-5 = 0.031, which Holm over six findings (the others undecided:
    # equal cases) cannot pass
    equal = [make_session(case_id, seed, 0.5 + 0.01 * ((seed * 3 + case_id) % 7), 100, True)
             for case_id in range(1, 7) for seed in range(10)]
    findings = evaluate_findings(equal + paper_like(seeds=5, profile='symmetric', seed=1))
    control = {finding.key: finding for finding in findings}["e'"]
    assert control.p_value == pytest.approx(1 / 32)
    assert control.verdict == 'inconclusive'
    assert 'power' in control.reason and '0.0312' in control.reason


def test_finding_e_names_the_paired_test_it_runs():
    """(e) is described by the paired comparison it runs, as (a) is.

    Its test column said Mann-Whitney U (unpaired) while its effect reported matched pairs
    (docs/results.md before this fix).
    """
    findings = {finding.key: finding for finding in evaluate_findings(paper_like())}
    assert findings['e'].test.startswith('Wilcoxon signed-rank by seed and person'), \
        findings['e'].test
    assert findings['e'].test.endswith('intersection-union over 3')
    assert findings['a'].test.endswith('intersection-union over 4')


def test_the_results_title_counts_the_cases(tmp_path):
    from hrc_study.results_doc import write_results

    sessions = [session for session in paper_like(seeds=3) if session.case_id <= 4]
    write_results(sessions, tmp_path, 'hrc_results x', None, parse_priorities('human=1'),
                  resamples=50)
    assert (tmp_path / 'results.md').read_text().startswith(
        '# Results: 4 cases over seeds, with statistics')
