"""Behaviour cloning of a person from recordings (pure: numpy and torch, no rclpy).

The model is the one ``hrc_joystick_node.human_model`` loads (``input: model``): an MLP
(tanh) from the last ``history_steps`` states, newest first (the history starts filled with the
episode's first state), and the subtasks asked of the person (slider, pendulum, ball as 0/1)
to the stick command in [-1, 1]. :func:`features` builds exactly the inputs
``ClonedHuman.act`` builds at run time, so what is trained is what runs.

**What it learns from** (``CloneSettings.targets``): ``applied`` (default) -- every command the
sim applied in the period after each state (``EpisodeTrace.applied``: at the human's own rate,
one per slice, e.g. ten at 0.02 s), each a training pair with that state's inputs; ``command``
-- the ``HumanAction`` answering the state (the person's first command of the period), as
before the human acted at their own rate (with one command per period, as recorded at
``human_period`` 0.2 s, both are the same). The clone acts once a control period and holds
its command over the slices (``ClonedHuman``), so in least squares it learns the mean of
what the person applied in the period, not the snapshot at its start; the held-out error is
measured against the same targets.

Modelling choices (not facts): a deterministic policy fitted by mean squared error (the
person's motor noise and lapses are not modelled: the clone is their mean response, so it is
steadier than they are); ``history_steps`` 6 (1.2 s at 0.2 s) covers reaction delays of 0.1 to
0.8 s and the person's view of speeds; Adam, full-batch, weight decay, a fixed number of
epochs. The split is by subject (``Demonstration.subject``: the recorded subject id, else the
session), never by step: the held-out error is the error on people (or sessions) the model
never saw, as in the behaviour-cloned human models of human_aware_rl (Carroll et al. 2019).

:func:`response_lag` estimates how late a policy answers: the lag (s) at which the command
correlates best with the negated controlled quantity (beam angle for rotation, slider height
for translation), pooled over episodes, refined by a parabola through the peak.
"""

from dataclasses import dataclass
import math
import typing

from hrc_joystick_node.human_model import build_network, input_size, STATE_FIELDS
from hrc_joystick_node.sim_human import normalize_subtasks, SUBTASKS
import numpy
import torch

CONTROLLED = {'rotation': STATE_FIELDS.index('pendulum_angle'),
              'translation': STATE_FIELDS.index('slider_position')}
TARGETS = ('applied', 'command')   # what a clone learns from (module docstring)


@dataclass
class CloneSettings:
    """How a clone is trained."""

    history_steps: int = 6        # states of history (6 x 0.2 s = 1.2 s)
    hidden: typing.Tuple[int, ...] = (32, 32)   # hidden layer widths (tanh)
    epochs: int = 600             # full-batch Adam steps
    learning_rate: float = 3e-3   # Adam step size
    weight_decay: float = 1e-5    # L2 penalty (Adam's weight_decay)
    seed: int = 0                 # torch seed of the initial weights
    targets: str = 'applied'      # TARGETS: the applied slice commands, or the HumanAction


def subtask_flags(subtasks) -> typing.List[float]:
    """Return the 0/1 flags (slider, pendulum, ball) of the subtasks asked of the person."""
    known, _ = normalize_subtasks(subtasks)
    return [1.0 if name in known else 0.0 for name in SUBTASKS]


def features(states: numpy.ndarray, subtasks, history_steps: int) -> numpy.ndarray:
    """Return the model inputs at every step of one episode (steps x input_size)."""
    states = numpy.asarray(states, dtype=float)
    padded = numpy.concatenate([numpy.repeat(states[:1], history_steps - 1, axis=0), states])
    columns = [padded[history_steps - 1 - lag:len(padded) - lag] for lag in range(history_steps)]
    flags = numpy.tile(subtask_flags(subtasks), (len(states), 1))
    return numpy.concatenate(columns + [flags], axis=1)


def step_targets(trace, targets: str = 'applied') -> typing.List[numpy.ndarray]:
    """Return, per step of ``trace``, the commands learned from (``targets``, see TARGETS)."""
    if targets not in TARGETS:
        raise ValueError(f'targets: expected one of {TARGETS}, got {targets!r}')
    if targets == 'applied' and len(trace.applied) == len(trace.commands):
        return [numpy.asarray(values, dtype=float) for values in trace.applied]
    return [numpy.array([float(command)]) for command in trace.commands]


def period_commands(trace, targets: str = 'applied') -> numpy.ndarray:
    """Return, per step, the mean of the commands learned from (the person's held-equivalent)."""
    return numpy.array([float(numpy.mean(values)) for values in step_targets(trace, targets)])


def dataset(demonstrations, history_steps: int,
            targets: str = 'applied') -> typing.Tuple[numpy.ndarray, numpy.ndarray]:
    """Return (inputs, commands) of every driven step of ``demonstrations``.

    One row per command learned from: with ``targets`` 'applied' a step at the human's rate
    gives one row per applied slice command, all with the step's inputs.
    """
    inputs, commands = [], []
    for demonstration in demonstrations:
        for trace in demonstration.episodes:
            rows = features(trace.states, trace.subtasks, history_steps)
            per_step = step_targets(trace, targets)
            for step in numpy.flatnonzero(trace.driving):
                values = per_step[step]
                inputs.append(numpy.repeat(rows[step:step + 1], len(values), axis=0))
                commands.append(values)
    if not inputs:
        return numpy.zeros((0, input_size(history_steps))), numpy.zeros(0)
    return numpy.concatenate(inputs), numpy.concatenate(commands)


def split_by_subject(demonstrations, held_out: typing.Sequence[str]) -> tuple:
    """Return (training, held-out) demonstrations; ``held_out`` names subjects (or sessions)."""
    held = set(held_out)
    test = [item for item in demonstrations if item.subject in held or item.session_id in held]
    train = [item for item in demonstrations if item not in test]
    return train, test


def train_clone(demonstrations, settings: CloneSettings = None, on_epoch=None) -> tuple:
    """Fit the model to ``demonstrations``; return (config, state_dict, training RMSE).

    The config holds ``history_steps`` and ``hidden``; the caller adds the rest.
    ``on_epoch(done)``, if given, is called with 0 when the epochs start (the data set is
    built) and after each epoch (progress; it does not change the training).
    """
    settings = settings or CloneSettings()
    config = {'history_steps': int(settings.history_steps),
              'hidden': [int(width) for width in settings.hidden]}
    inputs, targets = dataset(demonstrations, settings.history_steps, settings.targets)
    if len(targets) == 0:
        raise ValueError('no driven step to learn from')
    threads = torch.get_num_threads()
    torch.set_num_threads(1)          # a small MLP: more threads only contend for the cores
    torch.manual_seed(settings.seed)
    network = build_network(config)
    x = torch.tensor(inputs, dtype=torch.float64)
    y = torch.tensor(targets, dtype=torch.float64).unsqueeze(1)
    optimizer = torch.optim.Adam(network.parameters(), lr=settings.learning_rate,
                                 weight_decay=settings.weight_decay)
    if on_epoch is not None:
        on_epoch(0)
    for epoch in range(settings.epochs):
        optimizer.zero_grad()
        loss = torch.mean((network(x) - y) ** 2)
        loss.backward()
        optimizer.step()
        if on_epoch is not None:
            on_epoch(epoch + 1)
    with torch.no_grad():
        rmse = float(torch.sqrt(torch.mean((network(x) - y) ** 2)))
    torch.set_num_threads(threads)
    return config, network.state_dict(), rmse


def predict(network, trace, history_steps: int) -> numpy.ndarray:
    """Return the network's command at every step of one recorded episode (open loop)."""
    with torch.no_grad():
        rows = torch.tensor(features(trace.states, trace.subtasks, history_steps),
                            dtype=torch.float64)
        return network(rows).squeeze(1).numpy()


@dataclass
class ActionError:
    """Open-loop error of a model on recorded driven steps (normalized command units)."""

    rmse: float                   # root mean squared error of the command
    mae: float                    # mean absolute error
    zero_rmse: float              # RMSE of always answering 0 (the trivial baseline)
    correlation: float            # Pearson correlation of model and person
    steps: int


def action_error(network, demonstrations, history_steps: int,
                 targets: str = 'applied') -> ActionError:
    """Return the open-loop action error of ``network`` on ``demonstrations``.

    Against every command of ``targets`` (the model's command held over the period is
    compared with each applied slice command; ``steps`` counts those comparisons).
    """
    predicted, actual = [], []
    for demonstration in demonstrations:
        for trace in demonstration.episodes:
            model = predict(network, trace, history_steps)
            per_step = step_targets(trace, targets)
            for step in numpy.flatnonzero(trace.driving):
                predicted.append(numpy.full(len(per_step[step]), model[step]))
                actual.append(per_step[step])
    if not actual:
        return ActionError(math.nan, math.nan, math.nan, math.nan, 0)
    predicted, actual = numpy.concatenate(predicted), numpy.concatenate(actual)
    error = predicted - actual
    spread = float(predicted.std() * actual.std())
    correlation = float(numpy.mean((predicted - predicted.mean()) * (actual - actual.mean()))
                        / spread) if spread > 0 else math.nan
    return ActionError(float(numpy.sqrt(numpy.mean(error ** 2))),
                       float(numpy.mean(numpy.abs(error))),
                       float(numpy.sqrt(numpy.mean(actual ** 2))), correlation, int(len(actual)))


def response_lag(traces, commands, dof: str, control_period: float,
                 max_lag_steps: int = 8) -> float:
    """Return the lag (s) of best correlation between ``commands`` and the controlled quantity.

    ``traces``: EpisodeTrace objects (their states); ``commands``: one array per trace (the
    person's or a model's). Correlation of command[t] with -x[t - k] for k = 0..max_lag_steps,
    pooled over the driven steps of every episode; the peak is refined by a parabola.
    """
    column = CONTROLLED[dof]
    scores = []
    for lag in range(max_lag_steps + 1):
        pairs_u, pairs_x = [], []
        for trace, command in zip(traces, commands):
            signal = -trace.states[:, column]
            steps = numpy.arange(lag, len(signal))
            steps = steps[trace.driving[steps]]
            pairs_u.append(numpy.asarray(command)[steps])
            pairs_x.append(signal[steps - lag])
        u, x = numpy.concatenate(pairs_u), numpy.concatenate(pairs_x)
        spread = u.std() * x.std()
        scores.append(float(numpy.mean((u - u.mean()) * (x - x.mean())) / spread)
                      if spread > 0 else -math.inf)
    best = int(numpy.argmax(scores))
    offset = 0.0
    if 0 < best < max_lag_steps and all(map(math.isfinite, scores[best - 1:best + 2])):
        left, middle, right = scores[best - 1:best + 2]
        curvature = left - 2 * middle + right
        offset = 0.5 * (left - right) / curvature if curvature < 0 else 0.0
    return (best + offset) * control_period
