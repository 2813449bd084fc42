"""Figures of the report: Fig. 5 (training), Fig. 6 (actions), Fig. 7 (three factors).

matplotlib (Agg, no display), loaded only when a figure is drawn. Each figure is of one
simulated-human profile's sessions (:func:`hrc_bag.report.metrics.primary_profile`).
"""

import math

from hrc_common.cases import paper_case_ids
from hrc_common.contract import other_dof
import numpy

from hrc_bag.report.curves import first_human_episode, return_band
from hrc_bag.report.metrics import (by_case, FACTOR_AXES, factor_score, final_trace,
                                    median_session, three_factors)
from hrc_bag.report.records import kinds_known, STRATEGY_SHORT

PANELS = [('translation', '(a) robot: translation, human: rotation (cases 1, 3, 5)'),
          ('rotation', '(b) robot: rotation, human: translation (cases 2, 4, 6)')]
KIND_ROWS = [('training', 'training episodes (stochastic policy)'),
             ('judging', 'judging episodes (deterministic policy, judge convergence)')]


def load_pyplot():
    import matplotlib  # lazy: optional heavy dependency (about 1 s): only when a figure is drawn
    matplotlib.use('Agg')
    import matplotlib.pyplot as pyplot  # lazy: after use('Agg'): no display needed
    return pyplot


def _save(pyplot, figure, path) -> None:
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)


def _draw_band(axis, case_id: int, members, kind: str) -> None:
    """Draw one case's median return and inter-quartile band of ``kind`` episodes on ``axis``."""
    band = return_band(members, kind)
    if not band.episodes or all(math.isnan(value) for value in band.median):
        return
    seeds = f'{len(members)} seed{"" if len(members) == 1 else "s"}'
    line, = axis.plot(band.episodes, band.median, label=(
        f'case {case_id} ({seeds}, {STRATEGY_SHORT.get(members[0].strategy, "")})'))
    axis.fill_between(band.episodes, band.low, band.high, color=line.get_color(), alpha=0.2)
    # each session's last training episode: a tick on the median line
    stops = [stop for stop in band.stops if stop > 0]
    axis.plot(stops, [band.median[stop - 1] for stop in stops], '|', color=line.get_color(),
              markersize=9)
    joins = [join for join in map(first_human_episode, members) if join is not None]
    if kind == 'training' and joins and numpy.median(joins) > 1:
        axis.axvline(numpy.median(joins), color=line.get_color(), linestyle='--', linewidth=0.9)


def figure_training(sessions, profile: str, path) -> None:
    """Write Fig. 5: training and judging returns apart, median and IQR over all seeds."""
    pyplot = load_pyplot()
    groups = by_case(sessions, profile)
    figure, axes = pyplot.subplots(2, 2, figsize=(13, 8.4), sharex='col', squeeze=False)
    known = any(kinds_known(session) for members in groups.values() for session in members)
    for row, (kind, kind_title) in enumerate(KIND_ROWS):
        for axis, (dof, title) in zip(axes[row], PANELS):
            for case_id, members in groups.items():
                if members[0].robot_dof == dof:
                    _draw_band(axis, case_id, members, kind)
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
    _save(pyplot, figure, path)


def figure_actions(sessions, profile: str, path, seconds: float = 4.0,
                   start: float = 0.0) -> None:
    """Write Fig. 6: both actors' actions over ``seconds`` of evaluation, median seed per case."""
    pyplot = load_pyplot()
    figure, axes = pyplot.subplots(2, 3, figsize=(14, 6.6), squeeze=False, sharey=True)
    for axis in axes.flat:
        axis.set_visible(False)
    for case_id, members in by_case(sessions, profile).items():
        if case_id not in paper_case_ids():   # the paper's 2 x 3 panels
            continue
        axis = axes[(case_id + 1) % 2][(case_id - 1) // 2]
        axis.set_visible(True)
        chosen = median_session(members)
        trace = final_trace(chosen, seconds, start) if chosen is not None else {}
        human_dof = other_dof(members[0].robot_dof)
        for key, label in (('robot', f'robot ({members[0].robot_dof})'),
                           ('human', f'human ({human_dof})')):
            points = trace.get(key, [])
            if points:
                axis.step([time for time, _ in points], [value for _, value in points],
                          where='post', label=label)
        title = f'case {case_id}' + (f', median seed {chosen.seed}' if chosen else '')
        axis.set_title(title if trace else title + ': no evaluation trace', fontsize='medium')
        axis.set_xlim(start, start + seconds)
        axis.set_xlabel('time in the evaluation episode (s)')
        axis.grid(alpha=0.3)
        if axis.get_lines():
            axis.legend(loc='upper right', fontsize='small')
    axes[0][0].set_ylabel('normalized action')
    axes[1][0].set_ylabel('normalized action')
    figure.suptitle(f'Fig. 6: actions over {seconds:g} s of the first final evaluation '
                    f'episode of the seed with the median total error', fontsize='medium')
    _save(pyplot, figure, path)


def figure_three_factor(sessions, profile: str, path, factors=None) -> None:
    """Write Fig. 7: the three factors per strategy (outer is better) with 95% intervals.

    Radius 1 - 0.8 * value / largest value of the factor; the whisker on each axis spans the
    factor's BCa interval. ``factors``: :func:`three_factors` of the profile's sessions, if
    already computed.
    """
    if factors is None:
        factors = three_factors([session for session in sessions if session.profile == profile])
    largest = {key: max([value for entry in factors for value in (entry[key].estimate,
                                                                  entry[key].high)
                         if not math.isnan(value)], default=0.0) for key, _ in FACTOR_AXES}
    polygons = []
    for entry in factors:
        label = (f'{STRATEGY_SHORT.get(entry["strategy"], entry["strategy"] or "unknown")}: '
                 + ', '.join(f'{entry[key].estimate:.3g}' for key, _ in FACTOR_AXES))
        radii = [factor_score(entry[key].estimate, largest[key]) for key, _ in FACTOR_AXES]
        whiskers = [None if math.isnan(entry[key].low) or math.isnan(entry[key].high)
                    else (factor_score(entry[key].high, largest[key]),
                          factor_score(entry[key].low, largest[key]))
                    for key, _ in FACTOR_AXES]
        polygons.append((label, radii, whiskers))
    draw_three_factor(polygons, [text for _, text in FACTOR_AXES], path,
                      'Fig. 7: three factors per strategy, whiskers: 95% BCa intervals '
                      '(outer is better)',
                      'strategy: human-involved episodes, episodes, total error')


def draw_three_factor(polygons, axis_labels, path, title: str, legend_title: str,
                      size: float = 6.8) -> None:
    """Write a Fig. 7 radar: one polygon per ``(label, radii, whiskers)``, outer is better.

    ``radii``: :func:`factor_score` per axis (NaN drawn at the centre); ``whiskers``: per axis
    ``(low, high)`` radii of an interval, or None.
    """
    pyplot = load_pyplot()
    angles = [math.pi / 2 + 2 * math.pi * index / len(axis_labels)
              for index in range(len(axis_labels))]
    figure = pyplot.figure(figsize=(size, size))
    axis = figure.add_subplot(projection='polar')
    for label, radii, whiskers in polygons:
        radii = [0.0 if math.isnan(radius) else radius for radius in radii]
        line, = axis.plot(angles + angles[:1], radii + radii[:1], marker='o', label=label)
        axis.fill(angles + angles[:1], radii + radii[:1], color=line.get_color(), alpha=0.15)
        for angle, whisker in zip(angles, whiskers):
            if whisker is not None:
                axis.plot([angle, angle], list(whisker), color=line.get_color(), linewidth=2)
    axis.set_xticks(angles)
    axis.set_xticklabels(axis_labels)
    axis.set_ylim(0.0, 1.0)
    axis.set_yticklabels([])
    axis.legend(loc='upper center', bbox_to_anchor=(0.5, -0.06), fontsize='small',
                title=legend_title)
    axis.set_title(title, fontsize='medium')
    _save(pyplot, figure, path)
