"""Task decomposition tree and hierarchical reward (paper section III-B, eq. 1-5). Pure, no ROS.

The tree has levels (1 = highest priority), subtasks ``T_i^j`` and actions. A subtask connects to
lower-level subtasks (task-task connections, ``children``) and to actions (task-action
connections). The paper's decomposition rules are checked when a tree is built:

1. a subtask above the lowest level has one or more lower-level subtask branches;
2. every subtask traces down to an action (the tree's ends are actions);

plus what makes a tree usable: ids unique (subtasks and actions together), levels known,
children at a lower priority level than their parent (which also rules out cycles), actions
and executors known, reward shapes well defined.

Each subtask watches one state variable (``slider_position``, ``pendulum_angle``,
``ball_position``: attribute names of both ``PhysicsState`` and ``hrc_msgs/TaskState``) and has a
Gaussian reward component (eq. 3-5)::

    f = alpha / (sigma * sqrt(2 pi)) * exp(-((x - mu) / sigma)^2 / 2)

The robot's reward is the sum of the components of the subtasks active for it in the current
training step (eq. 2).
"""

from dataclasses import dataclass
import math
import os

import yaml

from hrc_common import bounded_yaml

# State variables a subtask may watch (PhysicsState / TaskState attribute, unit).
STATE_VARIABLES = {
    'slider_position': 'm',
    'pendulum_angle': 'rad',
    'ball_position': 'm',
}


class TaskTreeError(ValueError):
    """The task tree file breaks a decomposition rule or is malformed; the message says which."""


@dataclass(frozen=True)
class RewardShape:
    """Parameters of one Gaussian reward component (eq. 3-5), in the subtask's unit."""

    alpha: float
    sigma: float
    mu: float

    def value(self, x: float) -> float:
        """Return f(x) = alpha / (sigma sqrt(2 pi)) exp(-((x - mu) / sigma)^2 / 2)."""
        z = (x - self.mu) / self.sigma
        return self.alpha / (self.sigma * math.sqrt(2.0 * math.pi)) * math.exp(-0.5 * z * z)

    @property
    def peak(self) -> float:
        """Return the largest value f takes (at x = mu)."""
        return self.alpha / (self.sigma * math.sqrt(2.0 * math.pi))


@dataclass(frozen=True)
class Subtask:
    """One node T_i^j of the decomposition tree."""

    id: str
    level: int
    state_variable: str
    tolerance: float          # satisfied when mean |x - mu| over an episode is within this
    children: tuple           # ids of lower-level subtasks (task-task connections)
    actions: tuple            # ids of actions (task-action connections)
    direct_action: str = ''   # the action that drives this subtask most ('' if none)
    description: str = ''
    paper_symbol: str = ''
    unit: str = ''


@dataclass(frozen=True)
class Action:
    """One action A_k: a degree of freedom of the system ('translation' or 'rotation')."""

    id: str
    description: str = ''


class TaskTree:
    """A validated task decomposition tree with one reward preset selected.

    Build it with :meth:`from_file` / :meth:`from_dict`; both raise :class:`TaskTreeError` with
    every problem found.
    """

    def __init__(self, levels, subtasks, actions, executors, presets, preset):
        self.levels = tuple(levels)
        self.subtasks = {subtask.id: subtask for subtask in subtasks}
        self.actions = {action.id: action for action in actions}
        self.executors = tuple(executors)
        self.presets = dict(presets)
        if preset not in self.presets:
            raise TaskTreeError(f'unknown reward preset {preset!r}: the tree defines '
                                f'{sorted(self.presets)}')
        self.preset = preset
        self.shapes = self.presets[preset]

    # ----------------------------------------------------------------------------- loading

    @classmethod
    def from_file(cls, path, preset=None):
        """Load and validate a tree from a YAML file; ``preset`` None = the file's default."""
        return load_data_file(path, 'task tree file', TaskTreeError,
                              lambda document: cls.from_dict(document, preset))

    @classmethod
    def from_dict(cls, document, preset=None):
        """Build and validate a tree from the parsed YAML document."""
        if not isinstance(document, dict):
            raise TaskTreeError('the task tree must be a mapping with levels, actions, '
                                'executors, subtasks, reward_presets')
        problems = []
        missing = [key for key in ('levels', 'actions', 'executors', 'subtasks',
                                   'reward_presets') if key not in document]
        if missing:
            raise TaskTreeError(f'missing top-level keys {missing}')
        levels = document['levels']
        if (not isinstance(levels, list) or not levels
                or any(not isinstance(level, int) or isinstance(level, bool)
                       for level in levels)
                or levels != list(range(1, len(levels) + 1))):
            problems.append(f'levels must be 1, 2, ... without gaps, got {levels!r}')
            levels = []
        for key in ('actions', 'executors', 'subtasks'):
            if document[key] is not None and not isinstance(document[key], list):
                problems.append(f'{key} must be a list, got {_kind(document[key])}')
                document = {**document, key: []}
        actions = []
        for index, entry in enumerate(document['actions'] or []):
            if not isinstance(entry, dict) or not isinstance(entry.get('id'), str):
                problems.append(f'action #{index} needs an id')
                continue
            actions.append(Action(entry['id'], str(entry.get('description', ''))))
        executors = list(document['executors'] or [])
        if not all(isinstance(executor, str) for executor in executors):
            problems.append(f'executors must be a list of names, got {executors!r}')
            executors = [executor for executor in executors if isinstance(executor, str)]
        subtasks = []
        for index, entry in enumerate(document['subtasks'] or []):
            subtask, reasons = _parse_subtask(index, entry)
            problems += reasons
            if subtask is not None:
                subtasks.append(subtask)
        presets = {}
        raw_presets = document['reward_presets']
        if not isinstance(raw_presets, dict) or not raw_presets:
            problems.append('reward_presets must map preset names to shapes')
            raw_presets = {}
        for name, entry in raw_presets.items():
            shapes, reasons = _parse_preset(name, entry, [s.id for s in subtasks])
            problems += reasons
            presets[name] = shapes
        problems += check_rules(levels, subtasks, actions, executors)
        if problems:
            raise TaskTreeError('invalid task tree: ' + '; '.join(problems))
        if preset is None or preset == '':
            preset = document.get('default_preset', next(iter(presets)))
            if not isinstance(preset, str):
                raise TaskTreeError(f'default_preset must be a preset name, got {preset!r}')
        return cls(levels, subtasks, actions, executors, presets, preset)

    # ----------------------------------------------------------------------------- queries

    def subtasks_at(self, level: int) -> list:
        """Return the ids of the subtasks on ``level``, in file order."""
        return [s.id for s in self.subtasks.values() if s.level == level]

    def leaf_actions(self, subtask_id: str) -> set:
        """Return every action the subtask traces down to (through its children)."""
        subtask = self.subtasks[subtask_id]
        found = set(subtask.actions)
        for child in subtask.children:
            found |= self.leaf_actions(child)
        return found

    def direct_subtasks(self, action_id: str) -> list:
        """Return the ids of the subtasks whose direct action is ``action_id``."""
        return [s.id for s in self.subtasks.values() if s.direct_action == action_id]

    def check_subtask_ids(self, ids) -> None:
        """Raise TaskTreeError if any id is not a subtask of this tree."""
        unknown = [subtask_id for subtask_id in ids if subtask_id not in self.subtasks]
        if unknown:
            raise TaskTreeError(f'unknown subtasks {unknown}; the tree has '
                                f'{list(self.subtasks)}')

    def ordered(self, ids) -> list:
        """Return ``ids`` in the tree's order (level 1 first, then file order), unique."""
        wanted = set(ids)
        self.check_subtask_ids(wanted)
        return [s.id for level in self.levels for s in self.subtasks.values()
                if s.level == level and s.id in wanted]

    # ----------------------------------------------------------------------------- reward

    def error(self, subtask_id: str, state) -> float:
        """Return |x - mu| of the subtask's state variable in ``state`` (its unit)."""
        subtask = self.subtasks[subtask_id]
        return abs(float(getattr(state, subtask.state_variable)) - self.shapes[subtask_id].mu)

    def component(self, subtask_id: str, state) -> float:
        """Return f_i^j of one subtask for ``state`` (an object with the state attributes)."""
        subtask = self.subtasks[subtask_id]
        return self.shapes[subtask_id].value(float(getattr(state, subtask.state_variable)))

    def reward(self, state, active_ids) -> tuple:
        """Return (components, total): f of each active subtask, in order, and their sum (eq. 2).

        ``state`` is any object with the state-variable attributes (PhysicsState, TaskState).
        """
        components = [self.component(subtask_id, state) for subtask_id in active_ids]
        return components, float(sum(components))

    def peak_reward(self, active_ids) -> float:
        """Return the largest reward the active subtasks can give in one step."""
        return float(sum(self.shapes[subtask_id].peak for subtask_id in active_ids))

    # ----------------------------------------------------------------------------- rendering

    def render_text(self, executors=None, active=None) -> str:
        """Return the tree as indented text.

        ``executors`` maps action id -> 'robot'/'human' (a case's role assignment); ``active``
        marks the subtasks in the robot's reward with ``*``.
        """
        executors = executors or {}
        active = set(active or ())
        lines = [f'task decomposition tree (reward preset {self.preset!r}; '
                 f"* = in the robot's reward)"]

        def describe(subtask_id, depth):
            subtask = self.subtasks[subtask_id]
            shape = self.shapes[subtask_id]
            mark = '*' if subtask_id in active else ' '
            lines.append(f'{"    " * depth}{mark} [L{subtask.level}] {subtask.id} '
                         f'({subtask.paper_symbol or "-"}): {subtask.description} | '
                         f'{subtask.state_variable} ({subtask.unit or "?"}), '
                         f'alpha={shape.alpha:g} sigma={shape.sigma:g} mu={shape.mu:g}, '
                         f'tolerance={subtask.tolerance:g}')
            for child in subtask.children:
                describe(child, depth + 1)
            for action_id in subtask.actions:
                direct = ' (direct)' if action_id == subtask.direct_action else ''
                who = f' <- {executors[action_id]}' if action_id in executors else ''
                lines.append(f'{"    " * (depth + 1)}  action {action_id}{direct}{who}')

        for subtask_id in self.subtasks_at(self.levels[0]):
            describe(subtask_id, 0)
        return '\n'.join(lines)


def load_data_file(path, what: str, error_type, build):
    """Return ``build(document)`` of the YAML file ``path``; errors as ``error_type`` with path.

    A missing, unreadable, non-regular (a FIFO would block), binary or non-YAML file is refused
    with the reason, as is whatever ``build`` refuses with ``error_type``.
    """
    path = os.fspath(path)
    if os.path.exists(path) and not os.path.isfile(path):
        raise error_type(f'{what} {path} is not a regular file')
    try:
        with open(path, encoding='utf-8') as stream:
            document = bounded_yaml.load(stream.read(), path)
    except OSError as error:
        raise error_type(f'cannot read {what} {path}: {error}') from None
    except (UnicodeDecodeError, yaml.YAMLError) as error:
        raise error_type(f'{what} {path} is not valid YAML text: '
                         f'{bounded_yaml.describe(error)}') from None
    try:
        return build(document)
    except error_type as error:
        raise error_type(f'{path}: {error}') from None


def _parse_subtask(index, entry):
    """Return (Subtask or None, reasons) for one YAML subtask entry."""
    if not isinstance(entry, dict) or not isinstance(entry.get('id'), str):
        return None, [f'subtask #{index} needs an id']
    name = entry['id']
    reasons = []
    level = entry.get('level')
    if not isinstance(level, int) or isinstance(level, bool):
        reasons.append(f'subtask {name!r}: level must be an integer, got {level!r}')
        level = 0
    variable = entry.get('state_variable')
    if not isinstance(variable, str) or variable not in STATE_VARIABLES:
        reasons.append(f'subtask {name!r}: state_variable {variable!r} is not one of '
                       f'{sorted(STATE_VARIABLES)}')
        variable = ''
    tolerance = entry.get('tolerance')
    if (not isinstance(tolerance, (int, float)) or isinstance(tolerance, bool)
            or not math.isfinite(tolerance) or tolerance <= 0):
        reasons.append(f'subtask {name!r}: tolerance must be a positive number, '
                       f'got {tolerance!r}')
        tolerance = 0.0
    children = entry.get('children') or []
    actions = entry.get('actions') or []
    for key, value in (('children', children), ('actions', actions)):
        if _ids_in(value) != value:
            reasons.append(f'subtask {name!r}: {key} must be a list of ids, got {value!r}')
    children, actions = _ids_in(children), _ids_in(actions)
    direct_action = entry.get('direct_action', '')
    if not isinstance(direct_action, str):
        reasons.append(f'subtask {name!r}: direct_action must be an action id, got '
                       f'{direct_action!r}')
        direct_action = ''
    subtask = Subtask(id=name, level=level, state_variable=str(variable),
                      tolerance=float(tolerance), children=tuple(children),
                      actions=tuple(actions), direct_action=direct_action,
                      description=str(entry.get('description', '')),
                      paper_symbol=str(entry.get('paper_symbol', '')),
                      unit=str(entry.get('unit', STATE_VARIABLES.get(variable, ''))))
    return subtask, reasons


def _ids_in(value) -> list:
    """Return the string items of a YAML list (none of anything else)."""
    return [item for item in value if isinstance(item, str)] if isinstance(value, list) else []


def _kind(value) -> str:
    """Return a short description of a YAML value's type, for reasons."""
    return f'{type(value).__name__} {value!r}' if not isinstance(value, (dict, list)) \
        else type(value).__name__


def _parse_preset(name, entry, subtask_ids):
    """Return (shapes by subtask id, reasons) for one reward preset."""
    if not isinstance(entry, dict) or not isinstance(entry.get('shapes'), dict):
        return {}, [f'reward preset {name!r} needs a `shapes` mapping']
    reasons = []
    shapes = {}
    raw = entry['shapes']
    missing = [subtask_id for subtask_id in subtask_ids if subtask_id not in raw]
    if missing:
        reasons.append(f'reward preset {name!r}: no shape for subtasks {missing}')
    for subtask_id, values in raw.items():
        if subtask_id not in subtask_ids:
            reasons.append(f'reward preset {name!r}: shape for unknown subtask {subtask_id!r}')
            continue
        try:
            alpha, sigma, mu = (float(values[key]) for key in ('alpha', 'sigma', 'mu'))
        except (KeyError, TypeError, ValueError):
            reasons.append(f'reward preset {name!r}, subtask {subtask_id!r}: needs numbers '
                           f'alpha, sigma, mu, got {values!r}')
            continue
        if not all(math.isfinite(value) for value in (alpha, sigma, mu)):
            reasons.append(f'reward preset {name!r}, subtask {subtask_id!r}: '
                           f'alpha, sigma, mu must be finite')
        elif sigma <= 0:
            reasons.append(f'reward preset {name!r}, subtask {subtask_id!r}: sigma must be '
                           f'positive, got {sigma}')
        else:
            shapes[subtask_id] = RewardShape(alpha, sigma, mu)
    return shapes, reasons


def check_rules(levels, subtasks, actions, executors) -> list:
    """Return every way the tree breaks the decomposition rules (empty if none)."""
    problems = []
    action_ids = [action.id for action in actions]
    subtask_ids = [subtask.id for subtask in subtasks]
    seen = set()
    for identifier in subtask_ids + action_ids:
        if identifier in seen:
            problems.append(f'id {identifier!r} is used more than once (ids must be unique '
                            f'across subtasks and actions)')
        seen.add(identifier)
    if not actions:
        problems.append('the tree has no actions')
    if not subtasks:
        problems.append('the tree has no subtasks')
    if not executors:
        problems.append('the tree names no executors')
    unknown_executors = [executor for executor in executors if executor not in ('robot', 'human')]
    if unknown_executors:
        problems.append(f'unknown executors {unknown_executors}: known are robot, human')
    by_id = {subtask.id: subtask for subtask in subtasks}
    lowest = levels[-1] if levels else None
    for subtask in subtasks:
        if levels and subtask.level not in levels:
            problems.append(f'subtask {subtask.id!r}: level {subtask.level} is not one of '
                            f'{list(levels)}')
        for child in subtask.children:
            if child not in by_id:
                problems.append(f'subtask {subtask.id!r}: child {child!r} is not a subtask')
            elif by_id[child].level <= subtask.level:
                problems.append(f'subtask {subtask.id!r} (level {subtask.level}): child '
                                f'{child!r} must be on a lower-priority level (a larger '
                                f'number), not level {by_id[child].level}')
        for action_id in subtask.actions:
            if action_id not in action_ids:
                problems.append(f'subtask {subtask.id!r}: action {action_id!r} is not an '
                                f'action of the tree ({action_ids})')
        if subtask.direct_action and subtask.direct_action not in subtask.actions:
            problems.append(f'subtask {subtask.id!r}: direct_action {subtask.direct_action!r} '
                            f'is not among its actions {list(subtask.actions)}')
        if lowest is not None and subtask.level < lowest and not subtask.children:
            problems.append(f'rule 1: subtask {subtask.id!r} on level {subtask.level} has no '
                            f'lower-level subtask branch (children)')
    if problems:
        return problems
    # Rule 2 (after the structure is sound, so the walk terminates: children go down levels).
    for subtask in subtasks:
        if not _traces_to_action(subtask.id, by_id):
            problems.append(f'rule 2: subtask {subtask.id!r} does not trace down to any action')
    for level in levels:
        if not any(subtask.level == level for subtask in subtasks):
            problems.append(f'level {level} has no subtask')
    return problems


def _traces_to_action(subtask_id, by_id) -> bool:
    """Return True when the subtask or one of its descendants connects to an action."""
    subtask = by_id[subtask_id]
    return bool(subtask.actions) or any(_traces_to_action(child, by_id)
                                        for child in subtask.children)
