"""One episode of the task for the environments: physics, roles, reward, observation. Pure.

Nothing here is a second implementation: :class:`TaskRun` only wires the cores the nodes use.

* physics and stepping: ``hrc_sim_node.physics.SliderPendulumBall`` (PyBullet) stepped through
  the engine's loop (``hrc_engine.loop.EpisodeLoop``: the sim's step protocol, the human
  answering each state at the human's rate), the robot's command from outside;
* roles, training steps, reward: ``hrc_agent_node`` (``params/cases.yaml`` resolved by
  ``strategies.load_cases``; the reward is ``TaskTree.reward`` of the step's subtasks on the
  state reached, eq. 2-5, exactly as ``AgentCore`` computes it);
* observation: ``hrc_agent_node.observation.observation_of`` ({B_y, P_z, S_x, a_partner}, plus
  the three rates when ``observe_rates``), where a_partner is the partner's command *applied in
  the last control period* (``applied_command``, the agent's default ``human_action_source``);
* the simulated human: the human node's per-step core ``hrc_joystick_node.human_core.HumanCore``
  with the simulated input (see :func:`make_human`).

Per-episode errors (mean |x - mu| of every subtask over the states reached, as ``AgentCore``
reports them) are kept so a learner can be judged by the strategies' criterion (a subtask is
satisfied when its mean error is within its tolerance, ``params/task_tree.yaml``).
"""

from dataclasses import dataclass

from hrc_agent_node.observation import applied_command, observation_of
from hrc_agent_node.config import AgentParams, CASES_FILE_NAME, share_file, TREE_FILE_NAME
from hrc_agent_node.strategies import load_cases, StrategyProgress
from hrc_agent_node.task_tree import TaskTree
from hrc_common.cases import case_problem
from hrc_common.contract import SimLimits
from hrc_common.params import checked, param, ParameterError, with_overrides
from hrc_engine.human import SimulatedHumanSide
from hrc_engine.loop import EpisodeLoop, PartnerSide
from hrc_joystick_node.human_core import HumanCore, HumanParams
from hrc_joystick_node.human_profile import load_profiles
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall
from hrc_sim_node.commands import wrench_on
from hrc_sim_node.protocol import HUMAN, roles, ROBOT

NO_HUMAN = 'none'
POPULATION_PREFIX = 'population:'
MODEL_PREFIX = 'model:'
RENDER_MODES = ['rgb_array']
SEED_LIMIT = 2 ** 31 - 1  # episode seeds are drawn from [0, this)


def check_render_mode(render_mode) -> None:
    """Raise ParameterError unless ``render_mode`` is None or one of RENDER_MODES."""
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ParameterError(f'render_mode {render_mode!r}: supported are None and '
                             f'{RENDER_MODES}')


@dataclass
class TaskParams:
    """Which case, training step and reward the environments pose (shared by both)."""

    case: int = param(2, "Case of params/cases.yaml (the paper's 1..6; 7-8 partners first): "
                         'strategy and which degree of freedom the robot drives (even cases: '
                         'rotation)', low=1)
    training_step: int = param(0, "Index of the case's training step (0 = first); -1 = the "
                                  'last: its subtasks make the reward, it says whether the '
                                  'human acts', low=-1, high=9)
    preset: str = param(AgentParams().preset, 'Reward preset of params/task_tree.yaml (paper = '
                                              'alpha 10, sigma 1: nearly flat in SI units; '
                                              'tuned = sigma scaled to each range)')
    observe_rates: bool = param(False, "Add dB_y/dt, dP_z/dt, dS_x/dt to the paper's "
                                       'observation {B_y, P_z, S_x, a_h}')

    def check(self) -> list:
        """Return why the case is not one of params/cases.yaml (the one case table), if so."""
        problem = case_problem(self.case)
        return [problem] if problem else []


@dataclass
class GymParams(TaskParams):
    """The Gymnasium environment's parameters: the task, plus who the human is."""

    human: str = param('paper', "The human in the environment when the step involves it: a "
                                "profile of params/sim_human.yaml ('paper', 'skilled', "
                                "'novice'), 'population:<profile>' for a person drawn from "
                                "that profile's population (by the reset seed), "
                                "'model:<path>' for a human model cloned from recordings "
                                "(hrc_joystick_node.human_model checkpoint), or 'none' (zero "
                                'command). A human model object may be passed instead '
                                '(argument human_model).')


def resolve_step(case, index: int):
    """Return the case's training step ``index`` (-1 = last), or raise ParameterError."""
    steps = case.steps
    if not -len(steps) <= index < len(steps):
        raise ParameterError(f'training_step {index}: case {case.case_id} has '
                             f'{len(steps)} training step(s) (0..{len(steps) - 1}, or -1)')
    return steps[index]


def make_human(spec: str, dof: str, seed: int, limits: SimLimits, involved: bool, subtasks):
    """Return the human side of the loop (``hrc_engine.loop``) named by ``spec``.

    ``spec``: 'none' (a human who answers zero), a profile name, 'population:<profile>'
    (person number ``seed`` of the population around that profile,
    ``hrc_joystick_node.population``) or 'model:<path>' (a cloned human model, the node's
    input ``model``). The core
    (``HumanCore``) is the one the human node runs: it resets the person at each new episode
    and runs fatigue and rest on the stamps (simulation time) it is given; ``limits``: the
    physics' control period and limits, as the node reads them from the sim.
    """
    if spec == NO_HUMAN:
        return PartnerSide(None, limits)
    common = dict(dof=dof, involved=involved, seed=int(seed))
    if spec.startswith(MODEL_PREFIX):
        params = HumanParams(input='model', model_file=spec[len(MODEL_PREFIX):], **common)
    elif spec.startswith(POPULATION_PREFIX):
        params = HumanParams(input='sim', profile=spec[len(POPULATION_PREFIX):],
                             person=int(seed), **common)
    else:
        params = HumanParams(input='sim', profile=spec, **common)
    core = HumanCore(checked(params), load_profiles())
    core.set_limits(limits)
    core.on_session(dof, involved, list(subtasks))
    # The node's input check: with input sim or model the selector takes that input (no
    # device, no /joy); until this first check the core answers zero.
    core.on_inputs(False, 'no device (environment)', False, 'no /joy (environment)')
    return SimulatedHumanSide(core)


class TaskRun:
    """The physics with the roles, reward and observation of one case's training step."""

    def __init__(self, params: TaskParams, physics_params: PhysicsParams = None):
        self.params = checked(params)
        physics_params = physics_params if physics_params is not None else PhysicsParams()
        self.agent_params = with_overrides(
            AgentParams(), case=params.case, preset=params.preset,
            observe_rates=params.observe_rates)
        self.limits = SimLimits.of(physics_params)   # the sim's, as every actor uses them
        self.tree = TaskTree.from_file(share_file(TREE_FILE_NAME), params.preset)
        self.case = load_cases(share_file(CASES_FILE_NAME), self.tree)[params.case]
        self.step_spec = resolve_step(self.case, params.training_step)
        # The strategies' judge of an episode (satisfied subtasks, the step's criterion).
        self.progress = StrategyProgress(self.case, self.tree)
        self.progress.step_index = self.step_spec.index
        self.dofs = roles(self.case.robot_dof)
        self.subtasks = {ROBOT: self.step_spec.robot_subtasks,
                         HUMAN: self.step_spec.human_subtasks}
        self.physics = SliderPendulumBall(physics_params)
        self.loop = None
        self.set_human(PartnerSide(None, self.limits))
        self.state = None
        self._error_sums = {}
        self._states_reached = 0

    @property
    def human_involved(self) -> bool:
        """Return whether the human acts in this training step."""
        return self.step_spec.human_involved

    @property
    def observation_size(self) -> int:
        """Return the length of an observation (4, or 7 with rates)."""
        return 7 if self.params.observe_rates else 4

    @property
    def steps_per_episode(self) -> int:
        """Return the control steps of an episode (200)."""
        return self.physics.params.steps_per_episode

    def set_human(self, human) -> None:
        """Take ``human``, a human side of the loop (``hrc_engine.loop``), on a new clock.

        The states' stamps (the human's clock: fatigue and rest run on them) start at 0.
        """
        self.loop = EpisodeLoop.on_physics(self.physics, human, self.dofs[ROBOT])
        self.loop.set_roles(self.dofs[ROBOT], self.dofs[HUMAN], self.human_involved,
                            self.subtasks[HUMAN])

    def reset(self, seed: int, episode: int = 0):
        """Start episode ``episode`` from the physics seeded with ``seed``; return the state."""
        self.state = self.loop.start(int(episode), int(seed)).state
        self._error_sums = {subtask_id: 0.0 for subtask_id in self.tree.subtasks}
        self._states_reached = 0
        return self.state

    def advance(self, robot_command: float) -> float:
        """Run one control period with the robot's normalized command; return the human's.

        Through the engine's loop: the human side answers the period's state (and, at the
        human's rate, each state within the period); a human that is not involved in the step
        sends nothing and counts as 0 (as the sim does). The state reached is :attr:`state`.
        """
        answer = self.loop.answer()
        robot = self.dofs[ROBOT]
        advanced = self.loop.step(wrench_on(robot, robot_command * self.limits.full_scale(robot)),
                                  answer)
        self.state = advanced.state
        self.human_applied = advanced.human_applied   # N or N*m, per slice of the period
        for subtask_id in self.tree.subtasks:
            self._error_sums[subtask_id] += self.tree.error(subtask_id, self.state)
        self._states_reached += 1
        return answer.command if answer is not None else 0.0

    def reward(self, actor: str) -> tuple:
        """Return (components by subtask id, total) of ``actor``'s reward on the state reached."""
        ids = self.subtasks[actor]
        components, total = self.tree.reward(self.state, ids)
        return dict(zip(ids, components)), total

    def observation(self, actor: str):
        """Return ``actor``'s observation: the state and the partner's applied command."""
        partner = HUMAN if actor == ROBOT else ROBOT
        partner_action = 0.0
        if self.human_involved:
            partner_action = applied_command(self.state, self.dofs[partner], self.limits)
        return observation_of(self.agent_params, self.state, partner_action)

    def episode_errors(self) -> dict:
        """Return {subtask id: mean |x - mu|} over the states reached so far in the episode."""
        reached = max(self._states_reached, 1)
        return {subtask_id: total / reached for subtask_id, total in self._error_sums.items()}

    @property
    def finished(self) -> bool:
        """Return True when the state reached ends the episode."""
        return bool(self.state.truncated or self.state.terminated)

    def render(self, render_mode):
        """Return an RGB image of the system when ``render_mode`` is 'rgb_array', else None."""
        return self.physics.render() if render_mode == 'rgb_array' else None

    def close(self):
        """Release the physics client."""
        self.physics.close()
