"""The paper's five findings, each as a pre-declared test on the sessions (pure, no ROS).

Each finding is a claim about cases (a case = a strategy and a role assignment). A claim that
needs several comparisons to be true at once ("task first beats human first *and* together, with
either role assignment") is tested as an intersection-union test: its p-value is the largest of
the one-sided component p-values, which needs no multiplicity correction within the finding
(Berger 1982). Across the findings the p-values are Holm-adjusted as one family.

Verdicts (alpha = 0.05 on Holm-adjusted p-values):

* holds: every component comparison is significant in the claimed direction;
* does not hold: some component is significant in the opposite direction (its reverse p-values
  form their own Holm family);
* inconclusive: neither, with the reason (which comparison is not significant, its effect);
  also when a case the claim needs has fewer than 2 sessions.

Claims (the paper's section V; cases within a role assignment compared, never across):

(a) task first gives the best team performance: total error of case 1 < cases 3, 5 and of
    case 2 < cases 4, 6 (Mann-Whitney U; effect: rank-biserial r);
(b) task first needs the least human involvement: human-involved episodes, same comparisons;
(c) human first converges fastest: episodes to convergence (right-censored at the limit) of
    case 3 < cases 1, 5 and case 4 < cases 2, 6 (logrank; effect: restricted-mean difference);
(d) case 5 fails or is worst: it converges in fewer than half of its seeds (exact binomial
    test against 1/2), or its total error is above every other case's (Mann-Whitney U); the
    disjunction's p-value is twice the smaller (Bonferroni over the two);
(e) the robot on rotation beats its swapped twin: total error of case 2 < 1, 4 < 3, 6 < 5;
    repeated for every other simulated-human profile present (the symmetric-perception
    control), as a separate finding (e').
"""

from dataclasses import dataclass, field
import math

import numpy
from scipy import stats

from hrc_study.sessions import measures
from hrc_study.statistics import holm, logrank_faster, mann_whitney_less, TestResult

ALPHA = 0.05
MIN_SESSIONS = 2


@dataclass
class Component:
    """One comparison inside a finding."""

    label: str              # e.g. 'case 2 vs case 4'
    result: TestResult


@dataclass
class Finding:
    """A finding with its test, effect, p-values and verdict."""

    key: str                # 'a'..'e', "e'" ...
    claim: str
    comparison: str
    test: str
    components: list = field(default_factory=list)
    p_value: float = math.nan           # the finding's raw p (claimed direction)
    p_reverse: float = math.nan         # raw p of the strongest reversal
    p_holm: float = math.nan
    p_reverse_holm: float = math.nan
    effect: str = ''
    verdict: str = 'inconclusive'
    reason: str = ''
    missing: list = field(default_factory=list)
    any_component: bool = False     # the claim needs one component (a disjunction), not all


class CaseData:
    """The per-session measures of every (profile, case) group."""

    def __init__(self, sessions):
        self.groups = {}
        for session in sessions:
            key = (session.profile, session.case_id)
            self.groups.setdefault(key, []).append(measures(session))

    def profiles(self) -> list:
        """Return the profiles present, the most frequent first (ties: by name)."""
        counts = {}
        for (profile, _), members in self.groups.items():
            counts[profile] = counts.get(profile, 0) + len(members)
        return sorted(counts, key=lambda profile: (-counts[profile], profile))

    def values(self, profile: str, case_id: int, key: str) -> list:
        """Return one measure of every session of a case."""
        return [member[key] for member in self.groups.get((profile, case_id), [])]

    def count(self, profile: str, case_id: int) -> int:
        """Return the number of sessions of a case."""
        return len(self.groups.get((profile, case_id), []))


def _intersection(finding: Finding) -> None:
    """Set the finding's p-values from its components (intersection-union)."""
    results = [component.result for component in finding.components]
    finding.p_value = max(result.p_value for result in results)
    finding.p_reverse = min(result.p_reverse for result in results)
    weakest = max(finding.components, key=lambda component: component.result.p_value)
    finding.effect = (f'weakest: {weakest.label}, {weakest.result.effect_name} = '
                      f'{weakest.result.effect:+.2f} ({weakest.result.detail})')


def _pairs_test(data: CaseData, profile: str, pairs, key: str, finding: Finding) -> Finding:
    """Fill ``finding`` with one-sided Mann-Whitney tests 'x lower than y' for (x, y) cases."""
    for x_case, y_case in pairs:
        result = mann_whitney_less(data.values(profile, x_case, key),
                                   data.values(profile, y_case, key))
        finding.components.append(Component(f'case {x_case} vs case {y_case}', result))
    _intersection(finding)
    return finding


def _convergence(data: CaseData, profile: str, case_id: int) -> tuple:
    return (data.values(profile, case_id, 'total_episodes'),
            data.values(profile, case_id, 'converged'))


def _missing(data: CaseData, profile: str, cases) -> list:
    return [case for case in cases if data.count(profile, case) < MIN_SESSIONS]


def finding_a(data: CaseData, profile: str) -> Finding:
    """Test (a): task first gives the best team performance."""
    finding = Finding('a', CLAIMS['a'],
                      'total error (final evaluation): case 1 < 3, 5 and case 2 < 4, 6',
                      'Mann-Whitney U, one-sided, intersection-union over 4 comparisons')
    return _pairs_test(data, profile, [(1, 3), (1, 5), (2, 4), (2, 6)], 'total_error', finding)


def finding_b(data: CaseData, profile: str) -> Finding:
    """Test (b): task first needs the least human involvement."""
    finding = Finding('b', CLAIMS['b'],
                      'human-involved episodes (training and its evaluation episodes): '
                      'case 1 < 3, 5 and case 2 < 4, 6',
                      'Mann-Whitney U, one-sided, intersection-union over 4 comparisons')
    return _pairs_test(data, profile, [(1, 3), (1, 5), (2, 4), (2, 6)],
                       'human_involved_episodes', finding)


def finding_c(data: CaseData, profile: str) -> Finding:
    """Test (c): human first converges fastest."""
    finding = Finding('c', CLAIMS['c'],
                      'episodes to convergence, censored at the limit: case 3 < 1, 5 and '
                      'case 4 < 2, 6', 'logrank, one-sided, intersection-union over 4 '
                      'comparisons')
    for x_case, y_case in [(3, 1), (3, 5), (4, 2), (4, 6)]:
        result = logrank_faster(*_convergence(data, profile, x_case),
                                *_convergence(data, profile, y_case))
        finding.components.append(Component(f'case {x_case} vs case {y_case}', result))
    _intersection(finding)
    return finding


def binomial_fails(successes: int, count: int) -> TestResult:
    """Test "the case converges in fewer than half of its sessions" (exact binomial)."""
    fewer = stats.binomtest(successes, count, 0.5, alternative='less').pvalue
    more = stats.binomtest(successes, count, 0.5, alternative='greater').pvalue
    return TestResult('exact binomial vs 1/2 (one-sided)', float(fewer), float(more),
                      0.5 - successes / count, '1/2 - proportion converged',
                      f'{successes}/{count} converged')


def finding_d(data: CaseData, profile: str) -> Finding:
    """Test (d): case 5 fails or is worst."""
    finding = Finding('d', CLAIMS['d'], 'case 5 converges in < 1/2 of its seeds; or its '
                      'total error is above cases 1-4 and 6',
                      'exact binomial (fails) or Mann-Whitney U intersection-union over 5 '
                      '(worst); Bonferroni over the two')
    converged = data.values(profile, 5, 'converged')
    fails = binomial_fails(int(sum(converged)), len(converged))
    worst = Finding('d-worst', '', '', '')
    _pairs_test(data, profile, [(other, 5) for other in (1, 2, 3, 4, 6)], 'total_error', worst)
    worst_result = TestResult('Mann-Whitney U', worst.p_value, worst.p_reverse, math.nan, '',
                              worst.effect)
    finding.any_component = True
    finding.components = [Component('case 5 fails', fails),
                          Component('case 5 worst', worst_result)]
    finding.p_value = min(1.0, 2 * min(fails.p_value, worst.p_value))
    finding.p_reverse = max(fails.p_reverse, worst.p_reverse)
    finding.effect = (f'fails: {fails.detail}; worst: {worst.effect}')
    return finding


def finding_e(data: CaseData, profile: str, key: str = 'e') -> Finding:
    """Test (e): the robot on rotation beats its swapped twin (under ``profile``)."""
    finding = Finding(key, CLAIMS['e'] + ('' if key == 'e' else f' (simulated human: {profile})'),
                      'total error: case 2 < 1, 4 < 3, 6 < 5',
                      'Mann-Whitney U, one-sided, intersection-union over 3 comparisons')
    _pairs_test(data, profile, [(2, 1), (4, 3), (6, 5)], 'total_error', finding)
    rotation = [value for case in (2, 4, 6) for value in data.values(profile, case,
                                                                      'total_error')]
    translation = [value for case in (1, 3, 5) for value in data.values(profile, case,
                                                                         'total_error')]
    if rotation and translation and numpy.nanmean(translation) > 0:
        reduction = 1 - numpy.nanmean(rotation) / numpy.nanmean(translation)
        finding.effect += f'; mean total error {100 * reduction:.0f}% lower (paper: 64%)'
    return finding


ALL_CASES = (1, 2, 3, 4, 5, 6)
CLAIMS = {'a': 'Learn task first gives the best team performance',
          'b': 'Learn task first needs the least human involvement',
          'c': 'Learn human first converges fastest',
          'd': 'Learn together with the robot on translation (case 5) fails or is worst',
          'e': 'The robot on rotation beats its swapped twin'}


def evaluate_findings(sessions, primary_profile: str = '', alpha: float = ALPHA) -> list:
    """Return the findings (a)-(e), and (e') per other profile, with Holm-adjusted verdicts."""
    data = CaseData(sessions)
    profiles = data.profiles()
    if not profiles:
        return []
    primary = primary_profile or ('paper' if 'paper' in profiles else profiles[0])
    builders = [finding_a, finding_b, finding_c, finding_d, finding_e]
    findings = []
    for builder in builders:
        key = builder.__name__[-1]
        missing = _missing(data, primary, ALL_CASES)
        if missing:
            findings.append(Finding(key, CLAIMS[key], '', '', missing=missing))
        else:
            findings.append(builder(data, primary))
    for index, profile in enumerate(other for other in profiles if other != primary):
        key = "e'" + "'" * index
        missing = _missing(data, profile, ALL_CASES)
        if missing:
            findings.append(Finding(key, f'{CLAIMS["e"]} (simulated human: {profile})', '', '',
                                    missing=missing))
        else:
            findings.append(finding_e(data, profile, key))
    _adjust_and_judge(findings, alpha)
    return findings


def _adjust_and_judge(findings, alpha: float) -> None:
    tested = [finding for finding in findings if not finding.missing]
    for finding, adjusted, reverse in zip(tested, holm(f.p_value for f in tested),
                                          holm(f.p_reverse for f in tested)):
        finding.p_holm, finding.p_reverse_holm = adjusted, reverse
    for finding in findings:
        if finding.missing:
            finding.verdict = 'inconclusive'
            finding.reason = (f'cases {finding.missing} have fewer than {MIN_SESSIONS} '
                              f'sessions')
        elif finding.p_holm < alpha:
            finding.verdict = 'holds'
            finding.reason = (f'every comparison significant (Holm p = '
                              f'{finding.p_holm:.3g} < {alpha})')
        elif finding.p_reverse_holm < alpha:
            reversed_component = min(finding.components,
                                     key=lambda component: component.result.p_reverse)
            finding.verdict = 'does not hold'
            finding.reason = (f'{reversed_component.label} goes the other way (Holm p = '
                              f'{finding.p_reverse_holm:.3g}; {reversed_component.result.detail})')
        else:
            finding.verdict = 'inconclusive'
            finding.reason = _inconclusive_reason(finding, alpha)


def _inconclusive_reason(finding: Finding, alpha: float) -> str:
    """Say which comparison keeps the finding from holding."""
    if finding.p_value < alpha:
        return (f'significant alone (raw p = {finding.p_value:.3g}) but not after Holm over '
                f'the findings (p = {finding.p_holm:.3g})')
    pick = min if finding.any_component else max
    deciding = pick(finding.components, key=lambda component: component.result.p_value)
    direction = ('points the claimed way' if deciding.result.p_value
                 < deciding.result.p_reverse else 'points the other way')
    return (f'{deciding.label} {direction} but is not significant (raw p = '
            f'{deciding.result.p_value:.3g}; {deciding.result.detail})')


def significance_note() -> str:
    """Return the rule text for the results document."""
    return (f'alpha = {ALPHA}, Holm-adjusted over the findings; a finding holds when all its '
            'comparisons are significant (intersection-union), does not hold when one is '
            'significant the other way, else inconclusive.')

