"""Strategy chooser: rank the learning strategies by a user's priorities (pure, no ROS).

The paper's Fig. 7 is meant "to select the desired learning strategy". Here the three factors
of each strategy (over the sessions of its cases, optionally of one role assignment) are

* ``human``: human involvement, the mean of human-involved episodes per session;
* ``time``: training time, the restricted mean of episodes to convergence up to the limit (for
  sessions stopped at the limit, their episode count: a lower bound of the true time);
* ``performance``: team performance, the mean total error of the final evaluation.

All three are "lower is better". Each factor is scored relative to the worst strategy on it,
``1 - value / worst`` (0 for the worst; a small absolute difference stays a small score
difference), and a strategy's score is the weighted mean of its factor scores with the user's
weights. Modelling choice: this relative scale, documented, not taken from the paper.

Uncertainty: a stratified bootstrap (sessions resampled within each case, seeded) repeats the
whole ranking; the chooser reports each factor's 95% interval, how often each strategy ranks
first, and for each neighbour in the ranking how often the better one stays ahead. When that
is below 95% the evidence does not separate the two, and the chooser says so.
"""

from dataclasses import dataclass, field
import math

import numpy

from hrc_bag.report.intervals import Interval
from hrc_bag.report.metrics import strategy_rank
from hrc_bag.report.records import measures, STRATEGY_SHORT

FACTORS = {'performance': ('total_error', 'team performance (total error)'),
           'human': ('human_involved_episodes', 'human involvement (human-involved episodes)'),
           'time': ('total_episodes', 'training time (episodes, restricted to the limit)')}
SEPARATION = 0.95
PRESETS = {'balanced': {'performance': 1, 'human': 1, 'time': 1},
           'performance first': {'performance': 3, 'human': 1, 'time': 1},
           'least human time': {'performance': 1, 'human': 3, 'time': 1},
           'fastest training': {'performance': 1, 'human': 1, 'time': 3}}


def parse_priorities(text: str) -> dict:
    """Parse 'performance=3,human=1,time=1' (or a preset name); raise ValueError with reasons."""
    if text in PRESETS:
        return dict(PRESETS[text])
    weights, reasons = {}, []
    for item in filter(None, (part.strip() for part in text.split(','))):
        name, _, value = item.partition('=')
        name = name.strip()
        if name not in FACTORS:
            reasons.append(f'unknown factor {name!r} (expected {", ".join(FACTORS)})')
            continue
        try:
            weight = float(value)
        except ValueError:
            reasons.append(f'{name}: weight {value!r} is not a number')
            continue
        if not math.isfinite(weight) or weight < 0:
            reasons.append(f'{name}: weight must be a finite number >= 0, got {value}')
            continue
        weights[name] = weight
    if not reasons and sum(weights.values()) <= 0:
        reasons.append('at least one weight must be > 0')
    if reasons:
        raise ValueError('; '.join(reasons))
    return {name: weights.get(name, 0.0) for name in FACTORS}


@dataclass
class Ranked:
    """One strategy in the ranking."""

    strategy: str
    score: float
    factors: dict                   # factor -> Interval (estimate and bootstrap 95% interval)
    first_share: float              # fraction of bootstrap resamples in which it ranks first
    ahead_of_next: float = math.nan  # fraction of resamples it scores above the next one


@dataclass
class Choice:
    """The chooser's answer."""

    weights: dict
    ranking: list                   # Ranked, best first
    explanation: list = field(default_factory=list)   # sentences
    separated: bool = True          # the best is separated from the second


def _factor_values(groups: dict) -> dict:
    """Return {strategy: {factor: mean over the strategy's sessions}}."""
    values = {}
    for strategy, cases in groups.items():
        pooled = [row for rows in cases.values() for row in rows]
        values[strategy] = {factor: float(numpy.nanmean([row[key] for row in pooled]))
                            for factor, (key, _) in FACTORS.items()}
    return values


def _scores(values: dict, weights: dict) -> dict:
    total = sum(weights.values())
    scores = {strategy: 0.0 for strategy in values}
    for factor in FACTORS:
        worst = max(values[strategy][factor] for strategy in values)
        for strategy in values:
            relative = 1 - values[strategy][factor] / worst if worst > 0 else 0.0
            scores[strategy] += weights[factor] * relative / total
    return scores


def choose(sessions, weights: dict, robot_dof: str = '', profile: str = '',
           resamples: int = 2000, seed: int = 0) -> Choice:
    """Rank the strategies of ``sessions`` by ``weights`` (see the module docstring)."""
    groups = {}
    for session in sessions:
        if (robot_dof and session.robot_dof != robot_dof) or \
                (profile and session.profile != profile):
            continue
        row = measures(session)
        groups.setdefault(session.strategy, {}).setdefault(session.case_id, []).append(row)
    if len(groups) < 2:
        raise ValueError(f'the chooser needs sessions of at least two strategies, got '
                         f'{sorted(groups)}')
    values = _factor_values(groups)
    scores = _scores(values, weights)
    generator = numpy.random.default_rng(seed)
    strategies = sorted(groups, key=strategy_rank)
    draws = {strategy: {factor: [] for factor in FACTORS} for strategy in strategies}
    draw_scores = {strategy: [] for strategy in strategies}
    for _ in range(resamples):
        resampled = {strategy: {case: [rows[index] for index in
                                       generator.integers(0, len(rows), len(rows))]
                                for case, rows in cases.items()}
                     for strategy, cases in groups.items()}
        resampled_values = _factor_values(resampled)
        resampled_scores = _scores(resampled_values, weights)
        for strategy in strategies:
            draw_scores[strategy].append(resampled_scores[strategy])
            for factor in FACTORS:
                draws[strategy][factor].append(resampled_values[strategy][factor])
    score_matrix = numpy.array([draw_scores[strategy] for strategy in strategies])
    firsts = numpy.bincount(score_matrix.argmax(axis=0), minlength=len(strategies))
    ranking = []
    for index, strategy in enumerate(strategies):
        factors = {}
        for factor in FACTORS:
            low, high = numpy.nanpercentile(draws[strategy][factor], [2.5, 97.5])
            count = sum(len(rows) for rows in groups[strategy].values())
            factors[factor] = Interval(values[strategy][factor], float(low), float(high), count)
        ranking.append(Ranked(strategy, scores[strategy], factors,
                              float(firsts[index] / resamples)))
    ranking.sort(key=lambda entry: -entry.score)
    for better, worse in zip(ranking, ranking[1:]):
        better.ahead_of_next = float(numpy.mean(
            numpy.asarray(draw_scores[better.strategy]) > numpy.asarray(
                draw_scores[worse.strategy])))
    choice = Choice(dict(weights), ranking)
    choice.separated = len(ranking) < 2 or ranking[0].ahead_of_next >= SEPARATION
    choice.explanation = _explain(choice)
    return choice


def _name(strategy: str) -> str:
    return f'{STRATEGY_SHORT.get(strategy, strategy)} ({strategy})'


def _explain(choice: Choice) -> list:
    ranking, weights = choice.ranking, choice.weights
    best = ranking[0]
    total = sum(weights.values())
    sentences = []
    if len(ranking) > 1:
        second = ranking[1]
        contributions = {}
        for factor in FACTORS:
            worst = max(entry.factors[factor].estimate for entry in ranking)
            if worst <= 0:
                continue
            contributions[factor] = weights[factor] / total * (
                second.factors[factor].estimate - best.factors[factor].estimate) / worst
        reason = max(contributions, key=contributions.get) if contributions else ''
        sentences.append(
            f'{_name(best.strategy)} ranks first (score {best.score:.2f} vs '
            f'{second.score:.2f} for {_name(second.strategy)}), mostly because of '
            f'{FACTORS[reason][1] if reason else "nothing"}: '
            + ', '.join(f'{FACTORS[factor][1].split(" (")[0]} '
                        f'{_describe(best.factors[factor])} vs '
                        f'{_describe(second.factors[factor])}' for factor in FACTORS) + '.')
        losing = [factor for factor, value in contributions.items() if value < 0]
        if losing:
            sentences.append(f'It is worse than {_name(second.strategy)} on '
                             + ', '.join(FACTORS[factor][1].split(' (')[0] for factor in losing)
                             + ', which the weights count less.')
        if choice.separated:
            sentences.append(f'The evidence separates them: first in '
                             f'{100 * best.first_share:.0f}% of the bootstrap resamples, ahead '
                             f'of the second in {100 * best.ahead_of_next:.0f}%.')
        else:
            sentences.append(f'The evidence does NOT separate {_name(best.strategy)} from '
                             f'{_name(second.strategy)}: ahead in only '
                             f'{100 * best.ahead_of_next:.0f}% of the bootstrap resamples '
                             f'(needs {100 * SEPARATION:.0f}%); treat them as equal under '
                             f'these priorities.')
    return sentences


def _describe(interval: Interval) -> str:
    decimals = 3 if abs(interval.estimate) < 10 else 0
    return (f'{interval.estimate:.{decimals}f} [{interval.low:.{decimals}f}, '
            f'{interval.high:.{decimals}f}]')


def choice_markdown(choice: Choice, title: str = '') -> str:
    """Return the choice as a Markdown table plus its explanation."""
    weights = ', '.join(f'{factor} = {weight:g}' for factor, weight in choice.weights.items())
    lines = [f'**{title}** (weights: {weights})' if title else f'Weights: {weights}', '',
             '| rank | strategy | score | total error | human-involved episodes | episodes '
             '| first in | ahead of next |', '|---|---|---|---|---|---|---|---|']
    for rank, entry in enumerate(choice.ranking, 1):
        ahead = '' if math.isnan(entry.ahead_of_next) else f'{100 * entry.ahead_of_next:.0f}%'
        lines.append(f'| {rank} | {_name(entry.strategy)} | {entry.score:.2f} | '
                     f'{_describe(entry.factors["performance"])} | '
                     f'{_describe(entry.factors["human"])} | '
                     f'{_describe(entry.factors["time"])} | {100 * entry.first_share:.0f}% | '
                     f'{ahead} |')
    lines += [''] + choice.explanation
    return '\n'.join(lines) + '\n'
