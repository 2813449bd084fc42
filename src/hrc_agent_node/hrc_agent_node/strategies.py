"""Learning strategies, the paper's six cases, and a session's progress through them. Pure.

A strategy is a sequence of training steps (``params/cases.yaml``). Each step says which
subtasks the robot's reward sums (eq. 6-10), whether the human acts, which subtasks the human is
asked to hold, and the condition that ends the step. A case binds a strategy to a role
assignment (which action the robot executes; the human executes the other).

The paper does not define its convergence condition nor "all lower-level subtasks satisfied".
Chosen here (and parameters of the agent):

* a subtask is **satisfied** in an episode when the mean of |x - mu| over the episode's states
  is within the subtask's ``tolerance`` (``params/task_tree.yaml``: slider 0.01 m, pendulum
  0.1 rad, ball 0.05 m). Measured in the task's own units, so the criterion does not depend on
  the reward preset (the paper's sigma = 1 reward is nearly flat; a reward threshold would be
  met by any policy at all);
* ``converged``: every subtask the step watches is satisfied in each of the last
  ``convergence_window`` episodes of the step (default 3: one episode can be lucky, three in a
  row with an exploring policy are not). A step watches its robot reward's subtasks unless it
  lists ``watch`` (responsibility-guided step 1 watches only the robot's direct subtask: alone,
  the robot cannot hold the subtask driven by the partner's action, see params/cases.yaml);
* ``lower_levels_satisfied``: every subtask below the highest level (the level-2 subtasks) is
  satisfied in each of the last ``satisfied_window`` episodes of the step (default 3).

Episodes are counted per step: the window restarts when a step begins, so a new reward is
judged only on episodes trained under it.

**The floor of the rule.** A step is judged on judging episodes, and every run of judging
episodes follows a trigger (an update, or ``judging_interval`` training episodes); a judging
episode that satisfies the step is followed by another one of the same frozen policy until the
window is full or one fails. So even a policy that satisfies the step from its first episode
needs a fixed number of episodes in the step: the rule's floor (:func:`episode_floor`), T + W
for a window W and T training episodes per trigger (T = 1 with ``judging_interval: 0``, since
PPO updates at every episode's end, and with ``judging_interval: 1``). In the last step of
every case the human acts in every episode, so the floor is the smallest possible count of
human-involved episodes there: **4** for W = 3 and T = 1, **5** for T = 2 (the study's
configurations).

A step with ``judge_first`` (the person's step of ``partners_first``, cases 7 and 8) judges the
policy it inherits on its first episode, before any training in the step: its floor is W
(**3**).

**Partners first** (cases 7, 8; not in the paper). A step with ``partner: population`` trains
with simulated people instead of the session's person; it must come before every step with the
person, and only a caller that supplies the population runs it
(``hrc_partners.partners_first``; AgentCore refuses otherwise). Its episodes are not the
person's time (``AgentCore.population_episodes``).

The in-a-row rule judges one policy on W episodes (different reset seeds and, with the human,
different behaviour) instead of W successive policies on one episode each; the policy it
declares converged is the one evaluated afterwards.
"""

from dataclasses import dataclass

from hrc_common.cases import check_case_table
from hrc_common.params import from_dict

from hrc_agent_node.config import AgentParams, CASES_FILE_NAME, share_file, TREE_FILE_NAME
from hrc_agent_node.task_tree import load_data_file, TaskTree, TaskTreeError

ADVANCE_CONDITIONS = ('converged', 'lower_levels_satisfied')
SELECTOR_PREFIX = 'direct:'
# Who acts as the human in a step where the human is involved: the session's person (the real
# one, or the study's simulated person), or a population of simulated people run in process
# before the person joins (the partners-first strategy; hrc_partners.partners_first).
PARTNERS = ('person', 'population')


class CasesError(ValueError):
    """The cases file is malformed or names something the tree does not have."""


@dataclass(frozen=True)
class TrainingStep:
    """One training step of a strategy, resolved for a case."""

    index: int
    name: str
    robot_subtasks: tuple   # subtask ids in the robot's reward, tree order
    human_involved: bool
    human_subtasks: tuple   # subtask ids the human is asked to hold, tree order
    advance: str            # one of ADVANCE_CONDITIONS
    watch: tuple = ()       # subtask ids the advance condition checks, tree order
    partner: str = 'person'  # who is the human when involved: one of PARTNERS
    judge_first: bool = False  # the step's first episode judges the policy it starts with

    @property
    def with_person(self) -> bool:
        """Return True when the session's person acts in this step (their time counts)."""
        return self.human_involved and self.partner == 'person'


@dataclass(frozen=True)
class Case:
    """A paper case: a strategy with a role assignment."""

    case_id: int
    strategy: str
    description: str
    robot_dof: str          # action (degree of freedom) the robot executes
    human_dof: str          # the other one, executed by the human
    steps: tuple            # TrainingStep, in order

    @property
    def executors(self) -> dict:
        """Return {action id: 'robot' | 'human'}."""
        return {self.robot_dof: 'robot', self.human_dof: 'human'}

    @property
    def first_person_step(self) -> int:
        """Return the index of the first step in which the person acts (len(steps): none)."""
        return next((step.index for step in self.steps if step.with_person), len(self.steps))

    @property
    def has_population_steps(self) -> bool:
        """Return True when a step trains with a simulated population (run before the person)."""
        return any(step.partner == 'population' for step in self.steps)


def load_cases(path, tree) -> dict:
    """Load every case of a cases file, resolved against ``tree``: {case id: Case}."""
    return load_data_file(path, 'cases file', CasesError,
                          lambda document: cases_from_dict(document, tree))


def session_case(params, tree: TaskTree = None, cases: dict = None):
    """Return ``(tree, Case)`` of an agent with ``params`` (AgentParams) without building it.

    The task tree and cases files the parameters name (else the installed ones), resolved as the
    agent resolves them. No torch: a runner asks what a case needs (the partners-first
    pre-training) before it imports the learner.
    """
    tree = tree or TaskTree.from_file(params.task_tree_file or share_file(TREE_FILE_NAME),
                                      params.preset)
    cases = cases or load_cases(params.cases_file or share_file(CASES_FILE_NAME), tree)
    if params.case not in cases:
        raise ValueError(f'case {params.case} is not defined; the cases file has {sorted(cases)}')
    return tree, cases[params.case]


def pretrains_with_population(agent_parameters: dict) -> bool:
    """Return True when the agent's case trains with simulated partners before the person.

    ``agent_parameters``: the agent node's parameters ({name: value}, as a session composes
    them). No torch: the session runner asks before it loads the pre-training (cases 7, 8).
    """
    params = from_dict(AgentParams, dict(agent_parameters, checkpoint_dir='', resume_from=''))
    return session_case(params)[1].has_population_steps


def cases_from_dict(document, tree) -> dict:
    """Resolve the parsed cases document against ``tree``; raise CasesError with every reason.

    The file's shape (case ids, strategy names, robot_action) is the contract's
    (``hrc_common.cases.check_case_table``); what is checked here is the strategies' steps
    against the tree.
    """
    actions = list(tree.actions)
    if len(actions) != 2:
        raise CasesError(f'cases assign one action to the robot and the other to the human; the '
                         f'tree has {len(actions)} actions {actions}')
    table, problems = check_case_table(document)
    cases = {}
    for case_id, spec in table.items():
        missing = [dof for dof in (spec.robot_dof, spec.human_dof) if dof not in actions]
        if missing:
            problems.append(f'case {case_id}: {", ".join(missing)} is not an action of the '
                            f'tree {actions}')
            continue
        try:
            cases[case_id] = _resolve_case(case_id, spec.strategy,
                                           document['strategies'][spec.strategy],
                                           spec.robot_dof, spec.human_dof, tree)
        except CasesError as error:
            problems.append(str(error))
    if problems:
        raise CasesError('invalid cases: ' + '; '.join(problems))
    return cases


def _resolve_case(case_id, strategy, entry, robot_action, human_action, tree) -> Case:
    """Resolve one strategy's steps for a role assignment."""
    if not isinstance(entry, dict) or not isinstance(entry.get('steps'), list) \
            or not entry['steps']:
        raise CasesError(f'strategy {strategy!r}: needs a non-empty list `steps`')
    steps = []
    for index, raw in enumerate(entry['steps']):
        where = f'case {case_id} ({strategy}) step {index}'
        if not isinstance(raw, dict):
            raise CasesError(f'{where}: a step is a mapping')
        advance = raw.get('advance')
        if advance not in ADVANCE_CONDITIONS:
            raise CasesError(f'{where}: advance {advance!r} is not one of {ADVANCE_CONDITIONS}')
        involved = raw.get('human_involved')
        if not isinstance(involved, bool):
            raise CasesError(f'{where}: human_involved must be true or false')
        robot = _resolve_ids(raw.get('robot_subtasks'), tree, robot_action, human_action, where)
        human = _resolve_ids(raw.get('human_subtasks') or [], tree, robot_action, human_action,
                             where)
        if not robot:
            raise CasesError(f'{where}: the robot needs at least one subtask in its reward')
        if not involved and human:
            raise CasesError(f'{where}: the human is not involved but has subtasks {human}')
        partner = raw.get('partner', 'person')
        if partner not in PARTNERS:
            raise CasesError(f'{where}: partner {partner!r} is not one of {PARTNERS}')
        if partner == 'population' and not involved:
            raise CasesError(f'{where}: partner population needs human_involved true')
        if partner == 'population' and any(earlier.with_person for earlier in steps):
            raise CasesError(f'{where}: a population step must come before every step with '
                             f'the person (it is trained before the person joins)')
        judge_first = raw.get('judge_first', False)
        if not isinstance(judge_first, bool):
            raise CasesError(f'{where}: judge_first must be true or false')
        if 'watch' in raw:
            watch = _resolve_ids(raw['watch'], tree, robot_action, human_action, where)
        elif advance == 'converged':
            watch = robot
        else:  # lower_levels_satisfied: every subtask below the highest level
            watch = [subtask_id for subtask_id, subtask in tree.subtasks.items()
                     if subtask.level > tree.levels[0]]
        if not watch:
            raise CasesError(f'{where}: the advance condition watches no subtask')
        steps.append(TrainingStep(index, str(raw.get('name', f'step {index}')), tuple(robot),
                                  involved, tuple(human), advance, tuple(watch), partner,
                                  judge_first))
    return Case(case_id, strategy, str(entry.get('description', '')), robot_action,
                human_action, tuple(steps))


def _resolve_ids(raw, tree, robot_action, human_action, where) -> list:
    """Resolve subtask ids and `direct:robot` / `direct:human` selectors, in tree order."""
    if not isinstance(raw, list):
        raise CasesError(f'{where}: subtask lists must be lists, got {raw!r}')
    ids = []
    for item in raw:
        if not isinstance(item, str):
            raise CasesError(f'{where}: subtask lists hold subtask ids, got {item!r}')
        if item.startswith(SELECTOR_PREFIX):
            who = item[len(SELECTOR_PREFIX):]
            if who not in ('robot', 'human'):
                raise CasesError(f'{where}: selector {item!r} must be direct:robot or '
                                 f'direct:human')
            ids += tree.direct_subtasks(robot_action if who == 'robot' else human_action)
        else:
            ids.append(item)
    try:
        return tree.ordered(ids)
    except TaskTreeError as error:
        raise CasesError(f'{where}: {error}') from None


def training_episodes_per_trigger(judging_interval: int = 0) -> int:
    """Return how many training episodes come before each run of judging episodes (at least).

    ``judging_interval`` N > 0: N. Otherwise one run follows each update, and PPO updates at
    the end of every training episode (SAC before each judging episode): 1.
    """
    return int(judging_interval) if judging_interval > 0 else 1


def episode_floor(window: int, training_per_trigger: int) -> int:
    """Return the fewest episodes a step can take (see the module doc): T + W."""
    return int(training_per_trigger) + int(window)


class StrategyProgress:
    """Where a session is in its case's training steps, and when to move on.

    Call :meth:`record` after every training episode with the mean error of every subtask; it
    tells whether the step's condition is met and moves to the next step (or finishes).
    """

    def __init__(self, case: Case, tree, convergence_window: int = 3,
                 satisfied_window: int = 3):
        self.case = case
        self.tree = tree
        self.convergence_window = int(convergence_window)
        self.satisfied_window = int(satisfied_window)
        self.step_index = 0
        self.finished = False
        # Per-episode {subtask id: satisfied} of the episodes of the current step.
        self.step_history = []

    @property
    def step(self) -> TrainingStep:
        """Return the current training step."""
        return self.case.steps[self.step_index]

    @property
    def is_last_step(self) -> bool:
        """Return True on the strategy's last training step."""
        return self.step_index == len(self.case.steps) - 1

    def satisfied(self, errors: dict) -> dict:
        """Return {subtask id: mean error within tolerance} for an episode's mean errors."""
        return {subtask_id: errors[subtask_id] <= subtask.tolerance
                for subtask_id, subtask in self.tree.subtasks.items()}

    def window(self, step: TrainingStep) -> int:
        """Return how many consecutive satisfying episodes the step's condition needs."""
        return self.convergence_window if step.advance == 'converged' else self.satisfied_window

    def condition_met(self) -> bool:
        """Return True when the current step's condition holds over its recent episodes."""
        step = self.step
        window = self.window(step)
        if len(self.step_history) < window:
            return False
        recent = self.step_history[-window:]
        return all(episode[subtask_id] for episode in recent
                   for subtask_id in step.watch)

    def last_episode_met(self) -> bool:
        """Return True when the last recorded episode satisfied every subtask the step watches."""
        if not self.step_history:
            return False
        return all(self.step_history[-1][subtask_id] for subtask_id in self.step.watch)

    def record(self, errors: dict) -> tuple:
        """Record a training episode; return (condition_met, event).

        ``errors`` maps every subtask id to its mean |x - mu| over the episode. ``event`` is
        ``'advanced'`` (the next step starts with the next episode), ``'finished'`` (the last
        step's condition held: training ends) or ``''``.
        """
        if self.finished:
            raise RuntimeError('the strategy already finished; no more training episodes')
        missing = [subtask_id for subtask_id in self.tree.subtasks if subtask_id not in errors]
        if missing:
            raise ValueError(f'episode errors lack subtasks {missing}')
        self.step_history.append(self.satisfied(errors))
        met = self.condition_met()
        if not met:
            return False, ''
        if self.is_last_step:
            self.finished = True
            return True, 'finished'
        self.step_index += 1
        self.step_history = []
        return True, 'advanced'

    def skip(self) -> None:
        """Move on to the next step with its condition unmet (a runner's budget ran out)."""
        if self.finished or self.is_last_step:
            raise RuntimeError('only a step before the last one can be skipped')
        self.step_index += 1
        self.step_history = []

    def state_dict(self) -> dict:
        """Return the progress as plain data (for checkpoints)."""
        return {'case_id': self.case.case_id, 'step_index': self.step_index,
                'finished': self.finished,
                'step_history': [dict(episode) for episode in self.step_history]}

    def load_state_dict(self, state: dict) -> None:
        """Restore progress saved by :meth:`state_dict`."""
        if state['case_id'] != self.case.case_id:
            raise ValueError(f'progress of case {state["case_id"]} cannot continue case '
                             f'{self.case.case_id}')
        if not 0 <= state['step_index'] < len(self.case.steps):
            raise ValueError(f'step index {state["step_index"]} out of range')
        self.step_index = int(state['step_index'])
        self.finished = bool(state['finished'])
        self.step_history = [dict(episode) for episode in state['step_history']]
