"""A human model cloned from recordings, loaded as a human input (``input: model``); no rclpy.

This module is the loading hook and the file format; training the model from bags is separate
work. A checkpoint is a ``.pt`` file written by :func:`save_human_model` and holding
only plain containers and tensors, so it loads with ``torch.load(weights_only=True)`` (no code
can run from the file)::

    {'format': 'hrc-human-model', 'version': 1,
     'config': {'history_steps': int,         # states of history the model sees (>= 1)
                'hidden': [int, ...],         # hidden layer widths of the MLP (tanh)
                'dof': 'translation'|'rotation',  # the degree of freedom it was cloned on
                'control_period': float,      # s, the period of the recordings
                'description': str},          # who was cloned, from which sessions
     'state_dict': {name: tensor}}            # the MLP's parameters

The network maps what the person saw, the last ``history_steps`` states (slider height and
speed, beam angle and rate, ball position and speed, newest first; the history starts filled
with the episode's first state) and the subtasks asked of them (slider, pendulum, ball as 0/1),
to the stick command (tanh output, in [-1, 1]). :class:`ClonedHuman` has the interface of
:class:`~hrc_joystick_node.sim_human.SimulatedHuman` (``reset``, ``act``), so the human node
and the in-process engine drive it the same way. Every problem of a file (not a checkpoint, a
pickle that needs code, missing or wrong fields, shapes that do not fit the config, non-finite
weights) is refused with every reason at once (ParameterError).
"""

import math
import pathlib
import typing

from hrc_common.dof import DOFS
from hrc_common.params import ParameterError
from hrc_joystick_node.sim_human import normalize_subtasks, SUBTASKS

FORMAT = 'hrc-human-model'
VERSION = 1
STATE_FIELDS = ('slider_position', 'slider_velocity', 'pendulum_angle',
                'pendulum_angular_velocity', 'ball_position', 'ball_velocity')
MAX_HISTORY = 256
MAX_WIDTH = 4096


def input_size(history_steps: int) -> int:
    """Return the network's input width for ``history_steps`` states."""
    return history_steps * len(STATE_FIELDS) + len(SUBTASKS)


def config_problems(config) -> typing.List[str]:
    """Return every reason why ``config`` is not a valid model config (empty if valid)."""
    if not isinstance(config, dict):
        return [f'config: expected a mapping, got {type(config).__name__}']
    problems = []
    known = {'history_steps', 'hidden', 'dof', 'control_period', 'description'}
    problems += [f'config: unknown field {name!r}' for name in sorted(set(config) - known)]
    steps = config.get('history_steps')
    if not isinstance(steps, int) or isinstance(steps, bool) or not 1 <= steps <= MAX_HISTORY:
        problems.append(f'config.history_steps: expected an integer in 1..{MAX_HISTORY}, got '
                        f'{steps!r}')
    hidden = config.get('hidden')
    if not isinstance(hidden, list) or not all(
            isinstance(width, int) and not isinstance(width, bool) and 1 <= width <= MAX_WIDTH
            for width in hidden):
        problems.append(f'config.hidden: expected a list of widths in 1..{MAX_WIDTH}, got '
                        f'{hidden!r}')
    if config.get('dof') not in DOFS:
        problems.append(f'config.dof: expected one of {DOFS}, got {config.get("dof")!r}')
    period = config.get('control_period')
    if not isinstance(period, (int, float)) or isinstance(period, bool) or not (
            0.0 < period <= 10.0):
        problems.append(f'config.control_period: expected seconds in (0, 10], got {period!r}')
    if not isinstance(config.get('description', ''), str):
        problems.append('config.description: expected a string')
    return problems


def build_network(config: dict):
    """Return the torch MLP a checkpoint of ``config`` holds the parameters of."""
    import torch  # lazy: torch (seconds), only when a cloned model is used

    layers, width = [], input_size(config['history_steps'])
    for hidden in config['hidden']:
        layers += [torch.nn.Linear(width, hidden), torch.nn.Tanh()]
        width = hidden
    layers += [torch.nn.Linear(width, 1), torch.nn.Tanh()]
    return torch.nn.Sequential(*layers).double()


def save_human_model(path, config: dict, state_dict: dict) -> None:
    """Write a checkpoint of the format above (checked before writing)."""
    import torch  # lazy: torch (seconds), only when a cloned model is used

    problems = config_problems(config)
    if problems:
        raise ParameterError('; '.join(problems), problems)
    tensors = {name: value.detach().cpu().clone() for name, value in state_dict.items()}
    torch.save({'format': FORMAT, 'version': VERSION, 'config': dict(config),
                'state_dict': tensors}, str(path))


def load_human_model(path) -> tuple:
    """Return (config, network in eval mode) from a checkpoint; ParameterError if refused."""
    import torch  # lazy: torch (seconds), only when a cloned model is used

    path = pathlib.Path(path)
    where = f'model_file {path}'
    try:
        document = torch.load(str(path), map_location='cpu', weights_only=True)
    except OSError as error:
        raise ParameterError(f'{where}: cannot read: {error.strerror or error}') from None
    except Exception as error:  # noqa: BLE001 - anything torch or pickle refuses
        first = str(error).strip().splitlines()[0] if str(error).strip() else type(error)
        raise ParameterError(f'{where}: not a human-model checkpoint loadable with '
                             f'weights_only=True (plain tensors and containers only): '
                             f'{first}') from None
    if not isinstance(document, dict):
        raise ParameterError(f'{where}: expected a mapping, got {type(document).__name__}')
    problems = []
    if document.get('format') != FORMAT:
        problems.append(f'format: expected {FORMAT!r}, got {document.get("format")!r}')
    if document.get('version') != VERSION:
        problems.append(f'version: expected {VERSION}, got {document.get("version")!r}')
    config = document.get('config')
    problems += config_problems(config)
    state_dict = document.get('state_dict')
    if not isinstance(state_dict, dict) or not all(
            isinstance(value, torch.Tensor) for value in state_dict.values()):
        problems.append('state_dict: expected a mapping of names to tensors')
    if problems:
        raise ParameterError('; '.join(f'{where}: {problem}' for problem in problems),
                             [f'{where}: {problem}' for problem in problems])
    network = build_network(config)
    expected = network.state_dict()
    for name, tensor in expected.items():
        if name not in state_dict:
            problems.append(f'state_dict: missing {name} of shape {tuple(tensor.shape)}')
        elif tuple(state_dict[name].shape) != tuple(tensor.shape):
            problems.append(f'state_dict.{name}: shape {tuple(state_dict[name].shape)} does '
                            f'not fit the config ({tuple(tensor.shape)})')
        elif not bool(torch.isfinite(state_dict[name]).all()):
            problems.append(f'state_dict.{name}: holds non-finite values')
    problems += [f'state_dict: unexpected {name}' for name in sorted(set(state_dict)
                                                                      - set(expected))]
    if problems:
        raise ParameterError('; '.join(f'{where}: {problem}' for problem in problems),
                             [f'{where}: {problem}' for problem in problems])
    network.load_state_dict({name: value.double() for name, value in state_dict.items()})
    network.eval()
    return dict(config), network


class ClonedHuman:
    """A cloned human model driving one degree of freedom, as a SimulatedHuman does.

    ``control_period``: the s between calls (the sim's control period, from its limits); no
    default. A model recorded at another period runs, with a note saying so.
    """

    def __init__(self, path, dof: str, seed: int = 0, *, control_period: float):
        self.config, self.network = load_human_model(path)
        self.path = str(path)
        self.dof = dof
        self.seed = int(seed)
        self.control_period = float(control_period)
        self.episode = None
        if self.config['dof'] != dof:
            self.note = (f'cloned on {self.config["dof"]}, driving {dof}')
        else:
            self.note = ''
        if not math.isclose(self.config['control_period'], control_period, rel_tol=1e-6):
            self.note += ('; ' if self.note else '') + (
                f'recorded at {self.config["control_period"]} s, run at {control_period} s')
        self.reset(0)

    def reset(self, episode: int, rest_seconds=None) -> None:
        """Start episode ``episode``: clear the history (the model is deterministic)."""
        self.episode = int(episode)
        self._history: typing.List[typing.List[float]] = []

    def act(self, state, subtasks, now=None) -> float:
        """Return the stick command in [-1, 1] for ``state`` given the assigned subtasks."""
        import torch  # lazy: torch (see build_network)

        known, _ = normalize_subtasks(subtasks)
        values = [float(getattr(state, name)) for name in STATE_FIELDS]
        if not self._history:
            self._history = [values] * self.config['history_steps']
        self._history = [values] + self._history[:self.config['history_steps'] - 1]
        features = [value for row in self._history for value in row]
        features += [1.0 if subtask in known else 0.0 for subtask in SUBTASKS]
        with torch.no_grad():
            command = float(self.network(torch.tensor(features, dtype=torch.float64))[0])
        if not math.isfinite(command):
            return 0.0
        return max(-1.0, min(1.0, command))
