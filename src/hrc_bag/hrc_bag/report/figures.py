"""Figures of the report: Fig. 5 (training), Fig. 6 (actions), Fig. 7 (three factors)."""

import math

from hrc_common.contract import DOFS, other_dof

from hrc_bag.report.metrics import (mean_curve, action_trace, FACTOR_AXES, factor_score,
                                    three_factors, training_curve)
from hrc_bag.report.tables import STRATEGY_TITLES


def _pyplot():
    import matplotlib  # lazy: optional heavy dependency (about 1 s): only when a figure is drawn
    matplotlib.use('Agg')
    import matplotlib.pyplot as pyplot  # lazy: after use('Agg'): no display needed
    return pyplot


def figure_training_curves(rows, path) -> None:
    """Write Fig. 5: training curves per case, marks where the human joins / reward changes."""
    pyplot = _pyplot()
    from matplotlib.ticker import MaxNLocator  # lazy: matplotlib: loaded by _pyplot() just before
    panels = [('translation', '(a) robot: translation, human: rotation'),
              ('rotation', '(b) robot: rotation, human: translation')]
    figure, axes = pyplot.subplots(1, 2, figsize=(13, 4.8), sharey=True)
    for axis, (dof, title) in zip(axes, panels):
        members = [row for row in rows if row.robot_dof == dof]
        for row in members:
            curves = [training_curve(session) for session in row.sessions]
            curves = [curve for curve in curves if curve['returns']]
            if not curves:
                continue
            means, spreads = mean_curve([curve['returns'] for curve in curves])
            episodes = list(range(1, len(means) + 1))
            label = f'case {row.case_id}' + (f' ({len(curves)} seeds)' if len(curves) > 1
                                             else '')
            line, = axis.plot(episodes, means, marker='.', label=label)
            if len(curves) > 1:
                axis.fill_between(episodes, [m - s for m, s in zip(means, spreads)],
                                  [m + s for m, s in zip(means, spreads)],
                                  color=line.get_color(), alpha=0.2)
            for curve in curves:
                for episode in curve['human_joins']:
                    axis.annotate('', xy=(episode, means[episode - 1]),
                                  xytext=(episode, means[episode - 1] + _arrow_length(means)),
                                  arrowprops={'arrowstyle': '->', 'color': line.get_color(),
                                              'lw': 1.5})
                for episode in curve['reward_changes']:
                    axis.axvline(episode - 0.5, color=line.get_color(), linestyle='--',
                                 linewidth=0.8)
        axis.set_title(title)
        axis.set_xlabel('training episode')
        axis.xaxis.set_major_locator(MaxNLocator(integer=True))
        axis.grid(alpha=0.3)
        if axis.get_lines():
            axis.legend(loc='lower right')
        else:
            axis.text(0.5, 0.5, 'no session of these cases', transform=axis.transAxes,
                      ha='center', va='center', color='gray')
    axes[0].set_ylabel('episode return (robot reward)')
    figure.suptitle('Fig. 5: training (judging episodes left out); arrows: the human joins; '
                    'dashed: the reward changes '
                    '(new training step)')
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)


def _arrow_length(values) -> float:
    finite = [value for value in values if not math.isnan(value)]
    spread = (max(finite) - min(finite)) if finite else 1.0
    return 0.12 * (spread or 1.0)


def figure_actions(rows, path, seconds: float = 4.0, start: float = 0.0) -> None:
    """Write Fig. 6: robot and human actions over ``seconds`` of an evaluation episode."""
    pyplot = _pyplot()
    columns = max(1, min(3, len(rows)))
    lines = max(1, math.ceil(len(rows) / columns))
    figure, axes = pyplot.subplots(lines, columns,
                                   figsize=(max(4.6 * columns, 7.5), 3.2 * lines + 0.6),
                                   squeeze=False, sharey=True)
    # the first session of each case (lowest seed) gives the trace
    traces = [action_trace(sorted(row.sessions, key=lambda member: member.seed)[0], seconds,
                           start) for row in rows]
    # one symmetric scale for all cases, so that their action sizes compare
    largest = max([abs(value) for trace in traces for key in ('robot', 'human')
                   for _, value in trace.get(key, [])] + [0.1])
    for index, axis in enumerate(axes.flat):
        if index >= len(rows):
            axis.set_visible(False)
            continue
        row, trace = rows[index], traces[index]
        human_dof = other_dof(row.robot_dof) if row.robot_dof in DOFS else '?'
        if trace:
            for key, label in (('robot', f'robot ({row.robot_dof or "?"})'),
                               ('human', f'human ({human_dof})')):
                points = trace[key]
                if points:
                    axis.step([time for time, _ in points], [value for _, value in points],
                              where='post', label=label)
            axis.set_title(f'case {row.case_id}, evaluation episode {trace["episode"]}')
        else:
            axis.set_title(f'case {row.case_id}: no evaluation episode')
        axis.set_xlim(start, start + seconds)
        axis.set_ylim(-1.1 * largest, 1.1 * largest)
        axis.set_xlabel('time in episode (s)')
        axis.grid(alpha=0.3)
        if axis.get_lines():
            axis.legend(loc='upper right', fontsize='small')
    axes[0][0].set_ylabel('normalized action')
    figure.suptitle(f'Fig. 6: actions of the robot and the human over {seconds:g} s of '
                    f'evaluation')
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)


def figure_three_factor(rows, path) -> None:
    """Write Fig. 7: the three-factor diagram, one polygon per strategy."""
    factors = three_factors(rows)
    largest = {key: max((entry[key][0] for entry in factors
                         if not math.isnan(entry[key][0])), default=0.0)
               for key, _ in FACTOR_AXES}
    polygons = []
    for entry in factors:
        label = STRATEGY_TITLES.get(entry['strategy'], entry['strategy'] or 'unknown')
        values = ', '.join(f'{entry[key][0]:.2f}' for key, _ in FACTOR_AXES)
        scores = [factor_score(entry[key][0], largest[key]) for key, _ in FACTOR_AXES]
        whiskers = []   # mean +- sample std over the sessions, where there is a spread
        for key, _ in FACTOR_AXES:
            mean, spread, count = entry[key]
            whiskers.append((factor_score(mean + spread, largest[key]),
                             factor_score(max(mean - spread, 0.0), largest[key]))
                            if count > 1 and spread > 0 else None)
        polygons.append((f'{label}: {values}', scores, whiskers))
    draw_three_factor(polygons, [text for _, text in FACTOR_AXES], path,
                      'Fig. 7: three-factor diagram (outer is better)',
                      'strategy: human-involved, total episodes, total error')


def draw_three_factor(polygons, axis_labels, path, title: str, legend_title: str,
                      size: float = 6.4) -> None:
    """Write a Fig. 7 radar: one polygon per ``(label, radii, whiskers)``, outer is better.

    ``radii``: :func:`factor_score` per axis (NaN drawn at the centre); ``whiskers``: per axis
    ``(low, high)`` radii of a spread or interval, or None. Shared by the bag report (mean and
    standard deviation) and the study (bootstrap intervals).
    """
    pyplot = _pyplot()
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
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)
