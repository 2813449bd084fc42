"""Fig. 5-7 of the study over seeds, and the convergence curves (matplotlib, Agg; no ROS)."""

import dataclasses
from dataclasses import dataclass
import math
import warnings

from hrc_bag.report import action_trace, factor_score
from hrc_bag.report.figures import draw_three_factor
from hrc_common.contract import other_dof, paper_case_ids
import numpy
from scipy import stats

from hrc_study.sessions import (final_block_start, kind_of, kinds_known, measures,
                                STRATEGY_SHORT)
from hrc_study.statistics import censored

PANELS = [('translation', '(a) robot: translation, human: rotation (cases 1, 3, 5)'),
          ('rotation', '(b) robot: rotation, human: translation (cases 2, 4, 6)')]


def _pyplot():
    import matplotlib  # lazy: matplotlib (about 1 s), only when a figure is drawn
    matplotlib.use('Agg')
    import matplotlib.pyplot as pyplot  # lazy: matplotlib, after use('Agg') (no display)
    return pyplot


def by_case(sessions, profile: str) -> dict:
    """Return {case_id: [SessionRecord]} of one profile."""
    groups = {}
    for session in sessions:
        if session.profile == profile:
            groups.setdefault(session.case_id, []).append(session)
    return dict(sorted(groups.items()))


def returns_of_kind(session, kind: str) -> list:
    """Return [(episode position, return)] of the ``kind`` episodes before the final block.

    The position counts every episode of training from 1 (training and judging episodes share
    one axis). Sessions whose summaries do not say their kind (bags before
    ``EpisodeSummary.kind``): every non-evaluation episode is 'training', none 'judging'.
    """
    points = []
    for index, episode in enumerate(session.episodes[:final_block_start(session)]):
        if kind_of(episode) == kind:
            points.append((index + 1, episode.episode_return))
    return points


def training_returns(session) -> list:
    """Return the returns of the training episodes before the final block (judging excluded)."""
    return [value for _, value in returns_of_kind(session, 'training')]


@dataclass
class ReturnBand:
    """Return per episode position across all sessions of a case (Fig. 5)."""

    episodes: list          # episode positions 1..longest session
    median: list            # median over the sessions (NaN before any session has a value)
    low: list               # 25th percentile over the sessions
    high: list              # 75th percentile
    running: list           # sessions still training at that position
    stops: list             # each session's last position (converged or stopped at the limit)


def return_band(sessions, kind: str = 'training') -> ReturnBand:
    """Return the median and inter-quartile range of ``kind`` returns per episode position.

    Every session counts at every position: after its last episode (it converged, or stopped at
    the episode limit) its last return is carried forward, and between two episodes of the
    kind (judging) the earlier value holds. No survivor averaging: the band is over all
    sessions that have had an episode of the kind by then; the band is the inter-quartile range
    (half of the sessions lie inside it), not an interval of the mean.
    """
    series = [returns_of_kind(session, kind) for session in sessions]
    lengths = [final_block_start(session) for session in sessions]
    longest = max(lengths, default=0)
    values = numpy.full((len(series), longest), numpy.nan)
    for row, points in enumerate(series):
        for position, value in points:
            values[row, position - 1:] = value
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)   # columns without a value yet
        low, median, high = (numpy.nanpercentile(values, quantile, axis=0).tolist()
                             if longest else [] for quantile in (25, 50, 75))
    running = [sum(1 for length in lengths if length >= position)
               for position in range(1, longest + 1)]
    return ReturnBand(list(range(1, longest + 1)), median, low, high, running, lengths)


KIND_ROWS = [('training', 'training episodes (stochastic policy)'),
             ('judging', 'judging episodes (deterministic policy, judge convergence)')]


def figure_training(sessions, profile: str, path) -> None:
    """Write Fig. 5: training and judging returns apart, median and IQR over all seeds."""
    pyplot = _pyplot()
    groups = by_case(sessions, profile)
    figure, axes = pyplot.subplots(2, 2, figsize=(13, 8.4), sharex='col', squeeze=False)
    known = any(kinds_known(session) for members in groups.values() for session in members)
    for row, (kind, kind_title) in enumerate(KIND_ROWS):
        for axis, (dof, title) in zip(axes[row], PANELS):
            for case_id, members in groups.items():
                if members[0].robot_dof != dof:
                    continue
                band = return_band(members, kind)
                if not band.episodes or all(math.isnan(value) for value in band.median):
                    continue
                line, = axis.plot(band.episodes, band.median, label=(
                    f'case {case_id} ({len(members)} seeds, '
                    f'{STRATEGY_SHORT.get(members[0].strategy, "")})'))
                axis.fill_between(band.episodes, band.low, band.high, color=line.get_color(),
                                  alpha=0.2)
                # each session's last training episode: a tick on the median line
                stops = [stop for stop in band.stops if stop > 0]
                axis.plot(stops, [band.median[stop - 1] for stop in stops], '|',
                          color=line.get_color(), markersize=9)
                joins = [_first_human_episode(member) for member in members]
                joins = [join for join in joins if join is not None]
                if kind == 'training' and joins and numpy.median(joins) > 1:
                    axis.axvline(numpy.median(joins), color=line.get_color(), linestyle='--',
                                 linewidth=0.9)
            axis.set_title(f'{title}\n{kind_title}', fontsize='medium')
            axis.grid(alpha=0.3)
            if axis.get_lines():
                axis.legend(loc='lower right', fontsize='small')
            elif kind == 'judging':
                axis.text(0.5, 0.5, 'no judging episodes recorded' if known else
                          'episode kinds not recorded (bags before EpisodeSummary.kind):\n'
                          'judging episodes are in the training row',
                          transform=axis.transAxes, ha='center', va='center',
                          fontsize='small')
            axis.set_xlabel('episode of training (training and judging episodes counted)')
        axes[row][0].set_ylabel('episode return (robot reward)')
    figure.suptitle('Fig. 5: median return over all seeds, band: inter-quartile range across '
                    'seeds\na session that stopped (converged or at the limit) is carried at '
                    'its last value (tick: where it stopped); dashed: median episode at which '
                    'the human joins', fontsize='medium')
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)


def _first_human_episode(session):
    for index, episode in enumerate(session.episodes[:final_block_start(session)]):
        if kind_of(episode) == 'training' and episode.human_involved:
            return index + 1
    return None


def median_session(members):
    """Return the session whose total error is the (lower) median of its case."""
    ranked = sorted((value, session.seed, session) for session, value in
                    ((session, measures(session)['total_error']) for session in members)
                    if not math.isnan(value))
    return ranked[(len(ranked) - 1) // 2][2] if ranked else None


def final_trace(session, seconds: float = 4.0) -> dict:
    """Return the robot and human actions of the first final-evaluation episode (Fig. 6)."""
    bag_session = session.extra.get('bag_session')
    if bag_session is None:
        return {}
    start = final_block_start(session)
    final_episodes = {episode.episode for episode in session.episodes[start:]}
    summaries = [summary for summary in bag_session.summaries
                 if summary.episode in final_episodes]
    return action_trace(dataclasses.replace(bag_session, summaries=summaries), seconds)


def figure_actions(sessions, profile: str, path, seconds: float = 4.0) -> None:
    """Write Fig. 6: both actors' actions over ``seconds`` of evaluation, median seed per case."""
    pyplot = _pyplot()
    groups = by_case(sessions, profile)
    figure, axes = pyplot.subplots(2, 3, figsize=(14, 6.6), squeeze=False, sharey=True)
    for axis in axes.flat:
        axis.set_visible(False)
    for case_id, members in groups.items():
        if case_id not in paper_case_ids():   # the paper's 2 x 3 panels
            continue
        axis = axes[(case_id + 1) % 2][(case_id - 1) // 2]
        axis.set_visible(True)
        chosen = median_session(members)
        trace = final_trace(chosen, seconds) if chosen is not None else {}
        human_dof = other_dof(members[0].robot_dof)
        for key, label in (('robot', f'robot ({members[0].robot_dof})'),
                           ('human', f'human ({human_dof})')):
            points = trace.get(key, [])
            if points:
                axis.step([time for time, _ in points], [value for _, value in points],
                          where='post', label=label)
        title = f'case {case_id}'
        if chosen is not None:
            title += f', median seed {chosen.seed}'
        axis.set_title(title if trace else title + ': no evaluation trace', fontsize='medium')
        axis.set_xlim(0, seconds)
        axis.set_xlabel('time in the evaluation episode (s)')
        axis.grid(alpha=0.3)
        if axis.get_lines():
            axis.legend(loc='upper right', fontsize='small')
    axes[0][0].set_ylabel('normalized action')
    axes[1][0].set_ylabel('normalized action')
    figure.suptitle(f'Fig. 6: actions over {seconds:g} s of the first final evaluation '
                    f'episode of the seed with the median total error', fontsize='medium')
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)


def figure_three_factor(choice, path) -> None:
    """Write Fig. 7: the three factors per strategy (outer is better) with 95% intervals.

    Radius 1 - 0.8 * value / largest value of the factor (hrc_bag's scale): the whisker on each
    axis spans the bootstrap interval of the factor. Drawn by hrc_bag's Fig. 7.
    """
    axes_keys = [('human', 'less human-involved\ntraining'), ('time', 'less total training'),
                 ('performance', 'higher team\nperformance')]
    largest = {key: max(max(entry.factors[key].estimate, entry.factors[key].high)
                        for entry in choice.ranking) for key, _ in axes_keys}
    polygons = []
    for entry in sorted(choice.ranking, key=lambda item: item.strategy):
        label = (f'{STRATEGY_SHORT.get(entry.strategy, entry.strategy)}: '
                 + ', '.join(f'{entry.factors[key].estimate:.3g}' for key, _ in axes_keys))
        radii = [factor_score(entry.factors[key].estimate, largest[key])
                 for key, _ in axes_keys]
        whiskers = [None if math.isnan(entry.factors[key].low)
                    or math.isnan(entry.factors[key].high)
                    else (factor_score(entry.factors[key].high, largest[key]),
                          factor_score(entry.factors[key].low, largest[key]))
                    for key, _ in axes_keys]
        polygons.append((label, radii, whiskers))
    draw_three_factor(polygons, [label for _, label in axes_keys], path,
                      'Fig. 7: three factors per strategy, whiskers: 95% bootstrap intervals '
                      '(outer is better)',
                      'strategy: human-involved episodes, episodes, total error', size=6.8)


def figure_convergence(sessions, profile: str, path) -> None:
    """Write the Kaplan-Meier curves: fraction of seeds not yet converged per episode."""
    pyplot = _pyplot()
    groups = by_case(sessions, profile)
    figure, axis = pyplot.subplots(figsize=(7.5, 4.6))
    for case_id, members in groups.items():
        values = [measures(member) for member in members]
        times = [value['total_episodes'] for value in values]
        events = [value['converged'] for value in values]
        style = '-' if members[0].robot_dof == 'rotation' else '--'
        if any(events):
            survival = stats.ecdf(censored(times, events)).sf
            grid = numpy.concatenate([[0.0], survival.quantiles])
            probabilities = numpy.concatenate([[1.0], survival.probabilities])
        else:
            grid, probabilities = numpy.array([0.0, max(times)]), numpy.array([1.0, 1.0])
        axis.step(grid, probabilities, where='post', linestyle=style,
                  label=f'case {case_id} ({sum(events)}/{len(events)} converged)')
    axis.axhline(0.5, color='gray', linewidth=0.7)
    axis.set_xlabel('episodes (training and its evaluation episodes)')
    axis.set_ylabel('fraction of seeds not converged')
    axis.set_ylim(-0.02, 1.02)
    axis.grid(alpha=0.3)
    axis.legend(fontsize='small')
    axis.set_title('Episodes to convergence (Kaplan-Meier; solid: robot on rotation)',
                   fontsize='medium')
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)
