"""The paper's five findings, each as a pre-declared test on the sessions (pure, no ROS).

Each finding is a claim about cases (a case = a strategy and a role assignment). A claim that
needs several comparisons to be true at once ("task first beats human first *and* together, with
either role assignment") is tested as an intersection-union test: its p-value is the largest of
the one-sided component p-values, which needs no multiplicity correction within the finding
(Berger 1982). Across the findings the p-values are Holm-adjusted as one family.

Verdicts (alpha = 0.05 on Holm-adjusted p-values):

* holds: every component comparison is significant in the claimed direction;
* does not hold: some component is significant in the opposite direction after Holm's
  correction over the finding's components (the reversal p of a finding is the smallest
  Holm-adjusted reverse p of its components; these then form their own Holm family across the
  findings);
* inconclusive: neither, with the reason (which comparison is not significant, its effect);
  also when a case the claim needs has fewer than 2 sessions.

Pairing: the same seed and simulated person run in every case, so when every session of the two
compared cases has its twin (same seed and ``human.person``) the comparison is paired: the
Wilcoxon signed-rank test for complete measures, the exact signed-rank test by sign flips on
the pairs for censored counts (:func:`hrc_study.statistics.paired_sooner`). Otherwise
(sessions that do not pair) the unpaired test (Mann-Whitney U, log-rank) is used, and the
test's name says which.

Measures: ``keys`` chooses what a finding compares ({'error': ..., 'human': ...,
'episodes': ...}, default :data:`MEASURED`); :mod:`hrc_study.robustness` runs the findings
again on the unit-free error and on the counts above each case's floor.

Censoring: a session that stops at the episode limit without converging has an unknown number
of episodes to convergence and an unknown number of human-involved episodes to convergence:
both are right-censored at the count reached and are compared by survival methods (a count
capped by the limit is not smaller because another part of the same session used the cap).

Claims (the paper's section V; cases within a role assignment compared, never across):

(a) task first gives the best team performance: total error of case 1 < cases 3, 5 and of
    case 2 < cases 4, 6 (Wilcoxon signed-rank; effect: matched rank-biserial r);
(b) task first needs the least human involvement: human-involved episodes until convergence
    (censored when the session did not converge), same comparisons (exact by pair: "fewer" =
    converged after fewer human-involved episodes; effect: restricted-mean difference);
(c) human first converges fastest: episodes to convergence (censored at the limit) of
    case 3 < cases 1, 5 and case 4 < cases 2, 6 (exact by pair);
(d) case 5 fails or is worst, contrasted with every other case (1, 2, 3, 4, 6): it converges
    later than each of them (exact by pair, intersection-union over the five), or its
    total error is above each of theirs (Wilcoxon signed-rank, intersection-union over the
    five); the disjunction's p-value is twice the smaller (Bonferroni over the two). It does
    not hold only when both branches are refuted (some case converges significantly later than
    case 5 *and* some case has a significantly larger error);
(e) the robot on rotation beats its swapped twin: total error of case 2 < 1, 4 < 3, 6 < 5;
    repeated for every other simulated-human profile present (the symmetric-perception
    control), as a separate finding (e').
"""

from dataclasses import dataclass, field, replace
import math

import numpy

from hrc_common.cases import paper_case_ids

from hrc_bag.report.records import measures
from hrc_study.statistics import (holm, logrank_faster, mann_whitney_less,
                                  paired_differences, paired_sooner, pairs_needed, TestResult,
                                  wilcoxon_less)

ALPHA = 0.05
MIN_SESSIONS = 2
# What the findings compare: the team's error, the person's episodes, every episode.
MEASURED = {'error': 'total_error', 'human': 'human_involved_episodes',
            'episodes': 'total_episodes'}
SOONER_TEST_WORDS = ('exact signed-rank by seed and person (log-rank when the sessions do not '
                     'pair), one-sided, intersection-union over 4')


@dataclass
class Component:
    """One comparison inside a finding."""

    label: str              # e.g. 'case 2 vs case 4'
    result: TestResult
    p_reverse_holm: float = math.nan    # its reverse p, Holm-adjusted within the finding


@dataclass
class Finding:
    """A finding with its test, effect, p-values and verdict."""

    key: str                # 'a'..'e', "e'" ...
    claim: str
    comparison: str
    test: str
    components: list = field(default_factory=list)
    p_value: float = math.nan           # the finding's raw p (claimed direction)
    p_reverse: float = math.nan         # p of the strongest reversal, Holm within the finding
    p_holm: float = math.nan
    p_reverse_holm: float = math.nan
    effect: str = ''
    verdict: str = 'inconclusive'
    reason: str = ''
    missing: list = field(default_factory=list)
    any_component: bool = False     # the claim needs one component (a disjunction), not all
    reversal: str = ''              # what goes the other way (when it does)
    branches: list = field(default_factory=list)    # a compound claim: each branch's verdict


class CaseData:
    """The per-session measures of every (profile, case) group, with each session's pair key.

    The pair key is (seed, simulated person): the same key in two cases is the same seed and
    person run under the two cases (the study's paired design).
    """

    def __init__(self, sessions):
        self.groups = {}
        self.keys = {}
        for session in sessions:
            key = (session.profile, session.case_id)
            self.groups.setdefault(key, []).append(measures(session))
            self.keys.setdefault(key, []).append((session.seed,
                                                  session.extra.get('person', -1)))

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

    def pair_keys(self, profile: str, case_id: int) -> list:
        """Return the (seed, person) of every session of a case, in the order of values()."""
        return list(self.keys.get((profile, case_id), []))

    def paired(self, profile: str, x_case: int, y_case: int):
        """Return the pair keys both cases share when every session has its twin, else None.

        Paired means: each case has each key once, the two key sets are equal, >= 2 pairs.
        """
        x_keys, y_keys = self.pair_keys(profile, x_case), self.pair_keys(profile, y_case)
        if len(set(x_keys)) != len(x_keys) or len(set(y_keys)) != len(y_keys) or \
                set(x_keys) != set(y_keys) or len(x_keys) < MIN_SESSIONS:
            return None
        return sorted(x_keys)

    def aligned(self, profile: str, case_id: int, key: str, pairs) -> list:
        """Return one measure of a case in the order of ``pairs`` (pair keys)."""
        by_key = dict(zip(self.pair_keys(profile, case_id), self.values(profile, case_id, key)))
        return [by_key[pair] for pair in pairs]


def compare_lower(data: CaseData, profile: str, x_case: int, y_case: int,
                  key: str) -> TestResult:
    """Test "case x's measure is lower than case y's": paired when the sessions pair."""
    pairs = data.paired(profile, x_case, y_case)
    if pairs is None:
        return mann_whitney_less(data.values(profile, x_case, key),
                                 data.values(profile, y_case, key))
    x, y = data.aligned(profile, x_case, key, pairs), data.aligned(profile, y_case, key, pairs)
    dz, needed = pairs_needed(numpy.asarray(x, float) - numpy.asarray(y, float))
    return replace(wilcoxon_less(x, y), dz=dz, pairs_needed=needed)


def compare_sooner(data: CaseData, profile: str, x_case: int, y_case: int,
                   time_key: str) -> TestResult:
    """Test "case x converges after less of ``time_key`` than case y" (censored counts).

    The count is observed when the session converged and right-censored otherwise; exact by
    pair when the sessions pair, else the plain log-rank test.
    """
    pairs = data.paired(profile, x_case, y_case)
    if pairs is None:
        return logrank_faster(data.values(profile, x_case, time_key),
                              data.values(profile, x_case, 'converged'),
                              data.values(profile, y_case, time_key),
                              data.values(profile, y_case, 'converged'))
    columns = [data.aligned(profile, case, key, pairs) for case in (x_case, y_case)
               for key in (time_key, 'converged')]
    dz, needed = pairs_needed(paired_differences(*columns))
    return replace(paired_sooner(*columns), dz=dz, pairs_needed=needed)


def _intersection(finding: Finding) -> None:
    """Set the finding's p-values from its components.

    Claimed direction: intersection-union, the largest component p. Reversal: the components'
    reverse p-values Holm-adjusted within the finding, the smallest of them.
    """
    results = [component.result for component in finding.components]
    finding.p_value = max(result.p_value for result in results)
    for component, adjusted in zip(finding.components,
                                   holm(result.p_reverse for result in results)):
        component.p_reverse_holm = adjusted
    reversed_most = min(finding.components, key=lambda component: component.p_reverse_holm)
    finding.p_reverse = reversed_most.p_reverse_holm
    finding.reversal = f'{reversed_most.label} goes the other way ({reversed_most.result.detail})'
    weakest = max(finding.components, key=lambda component: component.result.p_value)
    finding.effect = (f'weakest: {weakest.label}, {weakest.result.effect_name} = '
                      f'{weakest.result.effect:+.2f} ({weakest.result.detail})')


def _pairs_test(data: CaseData, profile: str, pairs, key: str, finding: Finding) -> Finding:
    """Fill ``finding`` with one-sided tests 'x lower than y' for the (x, y) cases."""
    for x_case, y_case in pairs:
        finding.components.append(Component(f'case {x_case} vs case {y_case}',
                                            compare_lower(data, profile, x_case, y_case, key)))
    _intersection(finding)
    return finding


def _sooner_test(data: CaseData, profile: str, pairs, time_key: str,
                 finding: Finding) -> Finding:
    """Fill ``finding`` with one-sided survival tests 'x converges sooner than y'."""
    for x_case, y_case in pairs:
        finding.components.append(Component(
            f'case {x_case} vs case {y_case}',
            compare_sooner(data, profile, x_case, y_case, time_key)))
    _intersection(finding)
    return finding


def _missing(data: CaseData, profile: str, cases) -> list:
    return [case for case in cases if data.count(profile, case) < MIN_SESSIONS]


def paired_test_words(comparisons: int) -> str:
    """Describe the test of a finding whose comparisons go through ``_pairs_test``."""
    return ('Wilcoxon signed-rank by seed and person (Mann-Whitney U when the sessions do not '
            f'pair), one-sided, intersection-union over {comparisons}')


def finding_a(data: CaseData, profile: str, keys: dict = MEASURED) -> Finding:
    """Test (a): task first gives the best team performance."""
    finding = Finding('a', CLAIMS['a'],
                      'total error (final evaluation): case 1 < 3, 5 and case 2 < 4, 6',
                      paired_test_words(4))
    return _pairs_test(data, profile, [(1, 3), (1, 5), (2, 4), (2, 6)], keys['error'], finding)


def finding_b(data: CaseData, profile: str, keys: dict = MEASURED) -> Finding:
    """Test (b): task first needs the least human involvement (censored counts)."""
    finding = Finding('b', CLAIMS['b'],
                      'human-involved episodes until convergence (training and judging '
                      'episodes; censored when the session did not converge): case 1 < 3, 5 '
                      'and case 2 < 4, 6', SOONER_TEST_WORDS)
    return _sooner_test(data, profile, [(1, 3), (1, 5), (2, 4), (2, 6)], keys['human'],
                        finding)


def finding_c(data: CaseData, profile: str, keys: dict = MEASURED) -> Finding:
    """Test (c): human first converges fastest."""
    finding = Finding('c', CLAIMS['c'],
                      'episodes to convergence, censored at the limit: case 3 < 1, 5 and '
                      'case 4 < 2, 6', SOONER_TEST_WORDS)
    return _sooner_test(data, profile, [(3, 1), (3, 5), (4, 2), (4, 6)], keys['episodes'],
                        finding)


OTHER_CASES = (1, 2, 3, 4, 6)


def finding_d(data: CaseData, profile: str, keys: dict = MEASURED) -> Finding:
    """Test (d): case 5 fails or is worst, contrasted with every other case."""
    finding = Finding('d', CLAIMS['d'], 'case 5 converges later than each of cases 1-4 and 6; '
                      'or its total error is above each of theirs',
                      'fails: exact signed-rank by pair, intersection-union over 5; worst: '
                      'Wilcoxon signed-rank, intersection-union over 5; Bonferroni over the '
                      'two')
    fails = Finding('d-fails', '', '', '')
    _sooner_test(data, profile, [(other, 5) for other in OTHER_CASES], keys['episodes'], fails)
    worst = Finding('d-worst', '', '', '')
    _pairs_test(data, profile, [(other, 5) for other in OTHER_CASES], keys['error'], worst)
    converged = data.values(profile, 5, 'converged')
    finding.any_component = True
    finding.components = [
        Component('case 5 fails (converges later than every other case)',
                  TestResult('exact signed-rank by pair', fails.p_value, fails.p_reverse,
                             math.nan,
                             '', f'{int(sum(converged))}/{len(converged)} of case 5 '
                             f'converged; {fails.effect}')),
        Component('case 5 worst (total error above every other case)',
                  TestResult('Wilcoxon signed-rank', worst.p_value, worst.p_reverse, math.nan,
                             '', worst.effect))]
    finding.p_value = min(1.0, 2 * min(fails.p_value, worst.p_value))
    # refuting a disjunction needs both branches refuted: the larger of the two reversal ps
    finding.p_reverse = max(fails.p_reverse, worst.p_reverse)
    finding.reversal = f'not failing: {fails.reversal}; not worst: {worst.reversal}'
    finding.effect = (f'fails: {finding.components[0].result.detail}; worst: {worst.effect}')
    finding.branches = [branch_verdict('case 5 fails', fails),
                        branch_verdict('case 5 worst', worst)]
    return finding


def branch_verdict(name: str, branch: Finding, alpha: float = ALPHA) -> str:
    """Say what one branch of a compound finding shows on its own (before the Holm family).

    Supported: its intersection-union p < alpha; refuted: one of its comparisons significant
    the other way (Holm within the branch); else undecided.
    """
    if branch.p_value < alpha:
        return f'{name}: supported on its own (p = {branch.p_value:.3g})'
    if branch.p_reverse < alpha:
        return (f'{name}: refuted on its own, {branch.reversal} (Holm p = '
                f'{branch.p_reverse:.3g})')
    return f'{name}: undecided on its own (p = {branch.p_value:.3g})'


def finding_e(data: CaseData, profile: str, key: str = 'e', keys: dict = MEASURED) -> Finding:
    """Test (e): the robot on rotation beats its swapped twin (under ``profile``)."""
    finding = Finding(key, CLAIMS['e'] + ('' if key == 'e' else f' (simulated human: {profile})'),
                      'total error: case 2 < 1, 4 < 3, 6 < 5', paired_test_words(3))
    _pairs_test(data, profile, [(2, 1), (4, 3), (6, 5)], keys['error'], finding)
    rotation = [value for case in (2, 4, 6) for value in data.values(profile, case,
                                                                      keys['error'])]
    translation = [value for case in (1, 3, 5) for value in data.values(profile, case,
                                                                         keys['error'])]
    if rotation and translation and numpy.nanmean(translation) > 0:
        reduction = 1 - numpy.nanmean(rotation) / numpy.nanmean(translation)
        finding.effect += f'; mean total error {100 * reduction:.0f}% lower (paper: 64%)'
    return finding


CLAIMS = {'a': 'Learn task first gives the best team performance',
          'b': 'Learn task first needs the least human involvement',
          'c': 'Learn human first converges fastest',
          'd': 'Learn together with the robot on translation (case 5) fails or is worst',
          'e': 'The robot on rotation beats its swapped twin'}


def evaluate_findings(sessions, primary_profile: str = '', alpha: float = ALPHA,
                      keys: dict = MEASURED) -> list:
    """Return the findings (a)-(e), and (e') per other profile, with Holm-adjusted verdicts.

    ``keys``: the measures compared (:data:`MEASURED` by default, any subset replaced).
    """
    keys = dict(MEASURED, **keys)
    data = CaseData(sessions)
    profiles = data.profiles()
    if not profiles:
        return []
    primary = primary_profile or ('paper' if 'paper' in profiles else profiles[0])
    builders = [finding_a, finding_b, finding_c, finding_d, finding_e]
    findings = []
    for builder in builders:
        key = builder.__name__[-1]
        missing = _missing(data, primary, paper_case_ids())
        if missing:
            findings.append(Finding(key, CLAIMS[key], '', '', missing=missing))
        else:
            findings.append(builder(data, primary, keys=keys))
    for index, profile in enumerate(other for other in profiles if other != primary):
        key = "e'" + "'" * index
        missing = _missing(data, profile, paper_case_ids())
        if missing:
            findings.append(Finding(key, f'{CLAIMS["e"]} (simulated human: {profile})', '', '',
                                    missing=missing))
        else:
            findings.append(finding_e(data, profile, key, keys=keys))
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
            finding.verdict = 'does not hold'
            finding.reason = (f'{finding.reversal} (Holm p = {finding.p_reverse_holm:.3g}, '
                              f'corrected within the finding and across the findings)')
        else:
            finding.verdict = 'inconclusive'
            finding.reason = _inconclusive_reason(finding, alpha)


def _power_note(finding: Finding) -> str:
    """Say when the deciding comparison is already at the smallest p its test can give."""
    pick = min if finding.any_component else max
    deciding = pick(finding.components, key=lambda component: component.result.p_value)
    floor = deciding.result.floor_p
    if floor > 0 and deciding.result.p_value <= floor * (1 + 1e-9):
        return (f'; power: {deciding.label} is at the smallest p its test can give on these '
                f'sessions ({floor:.3g}; {deciding.result.detail}): more seeds are needed to '
                f'decide it')
    return ''


def _inconclusive_reason(finding: Finding, alpha: float) -> str:
    """Say which comparison keeps the finding from holding (and when power is the reason)."""
    if finding.p_value < alpha:
        return (f'significant alone (raw p = {finding.p_value:.3g}) but not after Holm over '
                f'the findings (p = {finding.p_holm:.3g})' + _power_note(finding))
    pick = min if finding.any_component else max
    deciding = pick(finding.components, key=lambda component: component.result.p_value)
    if deciding.result.p_value == deciding.result.p_reverse:
        direction = 'shows no difference either way'     # e.g. no comparable event at all
    else:
        direction = ('points the claimed way' if deciding.result.p_value
                     < deciding.result.p_reverse else 'points the other way')
    return (f'{deciding.label} {direction} but is not significant (raw p = '
            f'{deciding.result.p_value:.3g}; {deciding.result.detail})' + power_words(deciding))


def power_words(component: Component) -> str:
    """Say how many pairs the deciding comparison would need (what "inconclusive" means)."""
    needed, dz = component.result.pairs_needed, component.result.dz
    if math.isnan(needed):
        return ''
    if math.isinf(needed):
        return '; power: no difference on average (dz = 0), no number of pairs would decide it'
    return (f'; power: dz = {dz:+.2f}, about {needed:.0f} pairs would give 80% power at '
            f'alpha {ALPHA} one-sided')


def significance_note() -> str:
    """Return the rule text for the results document."""
    return (f'alpha = {ALPHA}, Holm-adjusted over the findings; a finding holds when all its '
            'comparisons are significant (intersection-union), does not hold when one is '
            "significant the other way after Holm's correction over the finding's comparisons "
            '(and then over the findings), else inconclusive. Comparisons are paired by seed '
            'and simulated person when the sessions pair (Wilcoxon signed-rank; for censored '
            'counts the exact signed-rank test by sign flips on the pairs whose order is known, '
            'with the exact sign test beside it); counts of sessions that did not converge are '
            'right-censored.')

