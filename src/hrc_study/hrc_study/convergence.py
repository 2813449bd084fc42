"""The study's convergence figure: Kaplan-Meier curves of episodes to convergence per case.

The report's figures (Fig. 5-7) are :mod:`hrc_bag.report.figures`; this one is the study's
survival analysis (censored at the episode limit).
"""

from hrc_bag.report.figures import load_pyplot
from hrc_bag.report.metrics import by_case
from hrc_bag.report.records import measures
import numpy
from scipy import stats

from hrc_study.statistics import censored


def figure_convergence(sessions, profile: str, path) -> None:
    """Write the Kaplan-Meier curves: fraction of seeds not yet converged per episode."""
    pyplot = load_pyplot()
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
