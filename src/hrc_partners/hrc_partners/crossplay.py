"""Cross-play: every trained agent with every partner, over seeds (pure core, no rclpy).

Each cell is the mean total error (m + rad + m, the Table II sum) of an agent's frozen,
deterministic policy with a partner over ``episodes`` evaluation episodes, once per seed (the
seed changes the sim's initial states and the simulated person's noise; a population partner
draws a new person per episode); the cell's value is the mean over seeds with a Student-t 95 %
interval (``hrc_study.statistics.mean_interval``). An agent's "drop" with a partner is the
ratio of its cell to the cell of its training partner (``profile:paper`` for an agent trained
with that person, ``population:paper`` for one trained with the population around it): 1.0 =
as good as with what it trained with, 2.0 = twice the error.
"""

from dataclasses import dataclass, field
import json
import math
import pathlib
import typing

from hrc_common.params import ParameterError
from hrc_engine.offline import evaluate
from hrc_engine.partners import parse_specs, spec_problem
from hrc_study.statistics import mean_interval
import numpy



@dataclass(frozen=True)
class Agent:
    """A trained agent: a name, its checkpoint and the partner it trained with ('' unknown)."""

    name: str
    checkpoint: str
    training_partner: str = ''


def parse_agent(text: str) -> Agent:
    """Return the Agent of ``NAME=PATH[@PARTNER]``; the partner also comes from PATH's .json.

    ``train_partners_agents`` writes ``<stem>.json`` beside ``<stem>.pt`` with the training
    partner; an ``@PARTNER`` given on the command line wins.
    """
    name, equals, rest = text.partition('=')
    if not equals or not name or not rest:
        raise ParameterError(f'agent {text!r}: expected NAME=CHECKPOINT[@PARTNER]')
    path, _, partner = rest.partition('@')
    if not pathlib.Path(path).is_file():
        raise ParameterError(f'agent {text!r}: no such checkpoint {path}')
    if not partner:
        sidecar = pathlib.Path(path).with_suffix('.json')
        if sidecar.is_file():
            try:
                partner = str(json.loads(sidecar.read_text()).get('training_partner', ''))
            except (ValueError, AttributeError):
                partner = ''
    if partner and spec_problem(partner):
        raise ParameterError(f'agent {name}: training partner: {spec_problem(partner)}')
    return Agent(name, path, partner)


def parse_agents(texts) -> typing.List[Agent]:
    """Return the agents of ``texts``; ParameterError listing every bad one at once."""
    agents, problems = [], []
    for text in texts:
        try:
            agents.append(parse_agent(text))
        except ParameterError as error:
            problems.append(str(error))
    names = [agent.name for agent in agents]
    problems += [f'agent name {name!r} given twice' for name in sorted(set(names))
                 if names.count(name) > 1]
    if problems:
        raise ParameterError('; '.join(problems), problems)
    return agents


@dataclass
class Matrix:
    """The cross-play result: errors per (agent, partner) and seed."""

    agents: typing.List[Agent]
    partners: typing.List[str]
    seeds: typing.List[int]
    episodes: int
    errors: typing.Dict[str, typing.Dict[str, typing.List[float]]] = field(default_factory=dict)

    def cell(self, agent: str, partner: str):
        """Return the cell's hrc_study Interval (mean over seeds, 95 % t interval)."""
        return mean_interval(self.errors[agent][partner])

    def drop(self, agent: Agent, partner: str) -> float:
        """Return the agent's error with ``partner`` over its error with its training partner."""
        if not agent.training_partner:
            return math.nan
        reference = self.cell(agent.name, agent.training_partner).estimate
        return self.cell(agent.name, partner).estimate / reference if reference > 0 else math.nan

    def as_dict(self) -> dict:
        """Return a JSON-able description with every seed's error, cell and drop."""
        cells = {}
        for agent in self.agents:
            cells[agent.name] = {}
            for partner in self.partners:
                interval = self.cell(agent.name, partner)
                cells[agent.name][partner] = {
                    'errors': self.errors[agent.name][partner], 'mean': interval.estimate,
                    'low': interval.low, 'high': interval.high,
                    'drop': self.drop(agent, partner)}
        return {'agents': [vars(agent) for agent in self.agents], 'partners': self.partners,
                'seeds': self.seeds, 'episodes_per_seed': self.episodes, 'cells': cells}


def matrix_columns(agents, partners) -> list:
    """Return the matrix's partners: ``partners``, then the agents' training partners not in it."""
    columns = list(partners)
    for agent in agents:
        if agent.training_partner and agent.training_partner not in columns:
            columns.append(agent.training_partner)
    return columns


def run_matrix(agents, partners, seeds, episodes: int, profiles_file=None,
               physics_overrides: dict = None, log=None) -> Matrix:
    """Evaluate every agent with every partner (its training partner added) for every seed."""
    columns = matrix_columns(agents, partners)
    specs = dict(zip(columns, parse_specs(columns)))
    matrix = Matrix(list(agents), columns, [int(seed) for seed in seeds], int(episodes))
    for agent in agents:
        matrix.errors[agent.name] = {}
        for partner in columns:
            values = [evaluate(agent.checkpoint, specs[partner], seed, episodes,
                               physics_overrides, profiles_file) for seed in seeds]
            matrix.errors[agent.name][partner] = values
            if log is not None:
                log(f'{agent.name} x {partner}: ' + ' '.join(f'{value:.4f}' for value in values))
    return matrix


def format_cell(interval) -> str:
    """Return 'mean [low, high]' with 4 decimals (n/a bounds for a single seed)."""
    if math.isnan(interval.low):
        return f'{interval.estimate:.4f}'
    return f'{interval.estimate:.4f} [{interval.low:.4f}, {interval.high:.4f}]'


def markdown(matrix: Matrix) -> str:
    """Return the matrix and the drops as Markdown tables."""
    header = '| agent (trained with) | ' + ' | '.join(matrix.partners) + ' |'
    rule = '|---' * (len(matrix.partners) + 1) + '|'
    lines = [f'Total error, mean over {len(matrix.seeds)} seeds [95 % t interval], '
             f'{matrix.episodes} evaluation episodes per seed', '', header, rule]
    for agent in matrix.agents:
        cells = [format_cell(matrix.cell(agent.name, partner)) for partner in matrix.partners]
        lines.append(f'| {agent.name} ({agent.training_partner or "?"}) | '
                     + ' | '.join(cells) + ' |')
    lines += ['', 'Drop: error with the partner / error with the training partner', '',
              header, rule]
    for agent in matrix.agents:
        drops = [matrix.drop(agent, partner) for partner in matrix.partners]
        lines.append(f'| {agent.name} ({agent.training_partner or "?"}) | ' + ' | '.join(
            'n/a' if math.isnan(value) else f'{value:.2f}x' for value in drops) + ' |')
    return '\n'.join(lines) + '\n'


def heatmap(matrix: Matrix, path) -> None:
    """Draw the matrix (log colour scale, mean and drop in each cell) to a PNG."""
    import matplotlib  # lazy: matplotlib (about 1 s), only when a figure is drawn
    matplotlib.use('Agg')
    import matplotlib.colors  # lazy: matplotlib, as above
    import matplotlib.pyplot as plt  # lazy: matplotlib, after use('Agg') (no display)

    values = numpy.array([[matrix.cell(agent.name, partner).estimate
                           for partner in matrix.partners] for agent in matrix.agents])
    positive = values[numpy.isfinite(values) & (values > 0)]
    norm = matplotlib.colors.LogNorm(vmin=positive.min(), vmax=positive.max()) \
        if positive.size and positive.min() < positive.max() else None
    figure, axes = plt.subplots(figsize=(1.6 + 1.5 * len(matrix.partners),
                                         1.2 + 0.55 * len(matrix.agents)))
    image = axes.imshow(values, cmap='viridis', norm=norm, aspect='auto')
    for row, agent in enumerate(matrix.agents):
        for column, partner in enumerate(matrix.partners):
            drop = matrix.drop(agent, partner)
            text = f'{values[row, column]:.3f}' + ('' if math.isnan(drop) else f'\n{drop:.1f}x')
            axes.text(column, row, text, ha='center', va='center', fontsize=7, color='white')
    axes.set_xticks(range(len(matrix.partners)), matrix.partners, rotation=30, ha='right',
                    fontsize=7)
    axes.set_yticks(range(len(matrix.agents)), [agent.name for agent in matrix.agents],
                    fontsize=7)
    figure.colorbar(image, ax=axes, label='total error (mean over seeds)')
    axes.set_title(f'cross-play: {len(matrix.seeds)} seeds x {matrix.episodes} episodes; '
                   'x = drop from the training partner', fontsize=8)
    figure.tight_layout()
    figure.savefig(str(path), dpi=120)
    plt.close(figure)


def write_outputs(matrix: Matrix, folder) -> typing.List[str]:
    """Write matrix.json, matrix.md and heatmap.png into ``folder``; return their paths."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / 'matrix.json').write_text(json.dumps(matrix.as_dict(), indent=2) + '\n')
    (folder / 'matrix.md').write_text(markdown(matrix))
    heatmap(matrix, folder / 'heatmap.png')
    return [str(folder / name) for name in ('matrix.json', 'matrix.md', 'heatmap.png')]
