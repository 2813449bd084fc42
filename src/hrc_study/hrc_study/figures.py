"""Fig. 5-7 of the study over seeds, and the convergence curves (matplotlib, Agg; no ROS)."""

import dataclasses
import math

from hrc_common.contract import other_dof
import numpy

from hrc_study.sessions import final_block_start, measures, STRATEGY_SHORT
from hrc_study.statistics import censored, mean_interval

PANELS = [('translation', '(a) robot: translation, human: rotation (cases 1, 3, 5)'),
          ('rotation', '(b) robot: rotation, human: translation (cases 2, 4, 6)')]


def _pyplot():
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as pyplot
    return pyplot


def by_case(sessions, profile: str) -> dict:
    """Return {case_id: [SessionRecord]} of one profile."""
    groups = {}
    for session in sessions:
        if session.profile == profile:
            groups.setdefault(session.case_id, []).append(session)
    return dict(sorted(groups.items()))


def training_returns(session) -> list:
    """Return the returns of the training (non-evaluation) episodes before the final block."""
    return [episode.episode_return
            for episode in session.episodes[:final_block_start(session)]
            if not episode.evaluation]


def return_band(sessions) -> tuple:
    """Return (episodes, mean, low, high, sessions left) of training returns per episode.

    The band is the 95% interval of the mean over the sessions still training at that episode.
    """
    curves = [training_returns(session) for session in sessions]
    length = max((len(curve) for curve in curves), default=0)
    mean, low, high, left = [], [], [], []
    for index in range(length):
        interval = mean_interval(curve[index] for curve in curves if index < len(curve))
        mean.append(interval.estimate)
        low.append(interval.low if interval.count > 1 else interval.estimate)
        high.append(interval.high if interval.count > 1 else interval.estimate)
        left.append(interval.count)
    return list(range(1, length + 1)), mean, low, high, left


def figure_training(sessions, profile: str, path) -> None:
    """Write Fig. 5: mean training return per episode with its 95% band across seeds."""
    pyplot = _pyplot()
    groups = by_case(sessions, profile)
    figure, axes = pyplot.subplots(1, 2, figsize=(13, 4.8), sharey=True)
    for axis, (dof, title) in zip(axes, PANELS):
        for case_id, members in groups.items():
            if members[0].robot_dof != dof:
                continue
            episodes, mean, low, high, _ = return_band(members)
            if not episodes:
                continue
            line, = axis.plot(episodes, mean, label=f'case {case_id} ({len(members)} seeds, '
                              f'{STRATEGY_SHORT.get(members[0].strategy, "")})')
            axis.fill_between(episodes, low, high, color=line.get_color(), alpha=0.2)
            joins = [_first_human_episode(member) for member in members]
            joins = [join for join in joins if join is not None]
            if joins and numpy.median(joins) > 1:
                axis.axvline(numpy.median(joins), color=line.get_color(), linestyle='--',
                             linewidth=0.9)
        axis.set_title(title, fontsize='medium')
        axis.set_xlabel('training episode')
        axis.grid(alpha=0.3)
        if axis.get_lines():
            axis.legend(loc='lower right', fontsize='small')
    axes[0].set_ylabel('episode return (robot reward)')
    figure.suptitle('Fig. 5: mean training return over seeds (judging episodes included), band: '
                    '95% interval of the mean '
                    '(sessions drop out as they converge); dashed: median episode at which '
                    'the human joins', fontsize='medium')
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)


def _first_human_episode(session):
    training = [episode for episode in session.episodes[:final_block_start(session)]
                if not episode.evaluation]
    for index, episode in enumerate(training):
        if episode.human_involved:
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
    from hrc_bag.report import action_trace

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
        if case_id not in range(1, 7):
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
    from hrc_bag.report import factor_score
    from hrc_bag.report.figures import draw_three_factor

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
    from scipy import stats

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
