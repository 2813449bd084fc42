"""The paper's cases, defined once in ``params/cases.yaml``: a strategy and the roles of each.

``CaseSpec``, ``CaseTableError``, ``load_case_table(path=None)``, ``check_case_table(document)``
-> (table, problems), ``case_table()`` (cached default), ``case_ids()``, ``paper_case_ids()``,
``case_problem(case)`` -> reason or None, ``cases_file_path()``. Pure: no rclpy.
"""

from dataclasses import dataclass
import functools

import yaml

from hrc_common import bounded_yaml
from hrc_common.contract import DOFS, other_dof
from hrc_common.paths import params_file

CASES_FILE_NAME = 'cases.yaml'


class CaseTableError(ValueError):
    """The cases file is missing or not of the expected shape."""


@dataclass(frozen=True)
class CaseSpec:
    """A paper case: a strategy and the role assignment (the human drives the other DOF)."""

    case_id: int
    strategy: str
    robot_dof: str
    human_dof: str
    # A step of its strategy trains with a simulated population (``partner: population``, the
    # partners-first strategy this project adds): not one of the paper's cases.
    population_steps: bool = False


def cases_file_path() -> str:
    """Return the default cases file path: ``cases.yaml`` of ``hrc_common.paths.params_dir()``."""
    return str(params_file(CASES_FILE_NAME))


def load_case_table(path=None) -> dict:
    """Return {case id: CaseSpec} from a cases file (default: ``cases_file_path()``).

    Checks the shape (``check_case_table``); every problem is reported at once in one
    CaseTableError.
    """
    path = path or cases_file_path()
    try:
        with open(path, 'rb') as stream:
            document = bounded_yaml.load(stream.read(), str(path))
    except OSError as error:
        raise CaseTableError(f'cannot read cases file {path}: {error.strerror}') from None
    except (yaml.YAMLError, UnicodeDecodeError) as error:
        raise CaseTableError(f'cases file {path} is not YAML: '
                             f'{bounded_yaml.describe(error)}') from None
    table, problems = check_case_table(document)
    if problems:
        raise CaseTableError(f'cases file {path}: ' + '; '.join(problems))
    return table


def check_case_table(document) -> tuple:
    """Return ({case id: CaseSpec} of the well-formed cases, [every problem]) of a parsed file.

    The shape: a mapping with ``strategies`` (a mapping of strategy names; what a strategy
    holds is the agent's, ``hrc_agent_node.strategies``) and ``cases`` (a non-empty mapping of
    positive integer ids to {strategy: a key of strategies, robot_action: a DOF}).
    """
    if not isinstance(document, dict):
        return {}, [f'expected a mapping with strategies and cases, got '
                    f'{type(document).__name__}']
    strategies = document.get('strategies')
    cases = document.get('cases')
    problems = []
    if not isinstance(strategies, dict):
        problems.append('strategies must be a mapping of strategy names')
        strategies = {}
    if not isinstance(cases, dict) or not cases:
        problems.append('cases must be a non-empty mapping of case ids')
        cases = {}
    table = {}
    for case_id, entry in cases.items():
        if isinstance(case_id, bool) or not isinstance(case_id, int) or case_id < 1:
            problems.append(f'case id {case_id!r} must be a positive integer')
            continue
        if not isinstance(entry, dict):
            problems.append(f'case {case_id}: expected a mapping, got {type(entry).__name__}')
            continue
        unknown = sorted(set(entry) - {'strategy', 'robot_action'}, key=str)
        if unknown:
            problems.append(f'case {case_id}: unknown keys {unknown}')
        strategy = entry.get('strategy')
        robot = entry.get('robot_action')
        known_strategy = isinstance(strategy, str) and strategy in strategies
        if not known_strategy:
            problems.append(f'case {case_id}: unknown strategy {strategy!r}; defined: '
                            f'{sorted(strategies, key=str)}')
        if robot not in DOFS:
            problems.append(f'case {case_id}: robot_action {robot!r} is not an action; the '
                            f'actions: {list(DOFS)}')
        elif known_strategy:
            steps = strategies[strategy].get('steps') if isinstance(strategies[strategy],
                                                                    dict) else None
            population = any(isinstance(step, dict) and step.get('partner') == 'population'
                             for step in (steps if isinstance(steps, list) else ()))
            table[case_id] = CaseSpec(case_id, strategy, robot, other_dof(robot), population)
    return dict(sorted(table.items())), problems


@functools.lru_cache(maxsize=None)
def case_table() -> dict:
    """Return the default case table (loaded once)."""
    return load_case_table()


def case_ids() -> tuple:
    """Return the ids of the defined cases, ascending."""
    return tuple(case_table())


def paper_case_ids() -> tuple:
    """Return the ids of the paper's cases of params/cases.yaml, ascending (1..6 in the file).

    A paper case: its strategy has no step with a simulated population (partners first, cases
    7-8, is this project's addition). The one definition for whatever studies, sweeps or
    figures "the paper's six cases".
    """
    return tuple(case_id for case_id, spec in case_table().items()
                 if not spec.population_steps)


def case_problem(case) -> str:
    """Return why ``case`` is not a defined case id, or None if it is."""
    ids = case_ids()
    if isinstance(case, bool) or not isinstance(case, int) or case not in ids:
        return f'case must be one of {min(ids)}..{max(ids)}, got {case!r}'
    return None
