"""The one in-process episode loop: the sim's steps, the human's and the robot's answers. Pure.

Every in-process user of the task steps it here, in the order the lockstep graph makes the
nodes act (``hrc_sim_node.stepper``): the in-process engine (which records the bags), the
offline runner (``hrc_engine.offline``: a partner instead of the human node's core), the
Gymnasium and PettingZoo environments (an external learner's command instead of the agent's)
and the partner tools and benchmarks, through those.

* :class:`EpisodeLoop`, step-wise: ``start`` an episode, then per control step the human's
  ``answer`` to the period's state and ``step`` with the robot's wrench: at the human's rate
  the human answers each slice state of the period while the robot's wrench holds.
* :func:`run_agent_episode` and :func:`run_agent_session`: the loop driven by an
  ``hrc_agent_node.agent_core.AgentCore`` (its episodes, updates and evaluation) until the
  session is done; a :class:`LoopObserver` hears every message the graph would publish.

A human side answers states: ``answers_states`` (False while it sits out: it sends nothing,
the sim awaits nothing), ``on_session(dof, involved, subtasks)``, ``start_episode(episode)``
and ``answer(episode, state, stamp_ns, slice_index) -> HumanAnswer``; the human node's core
(``hrc_engine.human.SimulatedHumanSide``) and an offline partner (:class:`PartnerSide`), for
example.
"""

from dataclasses import dataclass

from hrc_common.contract import InputSource
from hrc_sim_node.commands import wrench_on
from hrc_sim_node.protocol import ProtocolSettings, StepProtocol
from hrc_sim_node.stepper import SimStepper

SOURCE_SIMULATED = int(InputSource.SIMULATED)


@dataclass(frozen=True)
class HumanAnswer:
    """The human's answer to one state."""

    command: float          # normalized, [-1, 1]
    wrench: float           # N or N*m on ``dof``
    dof: str
    source: int             # HumanAction.SOURCE_*
    detail: str
    engaged: bool


class PartnerSide:
    """An offline partner as the human side of the loop.

    ``partner(state, subtasks) -> command in [-1, 1]`` on the human's degree of freedom
    (``hrc_engine.partners``; an object with a ``start_episode(episode)`` method is told each
    episode before it starts; one with ``takes_time`` true is also given ``now``, the state's
    stamp in s, as the human node's core gives the simulated person its clock). ``limits``:
    the sim's (``SimLimits``): a command's wrench is the command times the full scale of the
    human's degree of freedom; ``partner`` None answers zero. The partner is asked
    at every state the human answers (the period's state and, at the human's rate, each slice
    state) unless ``hold_over_slices``: then it acts on the period's state and its command
    holds over the period's slices (a model that acts once a control period).
    """

    def __init__(self, partner, limits, hold_over_slices: bool = False, detail: str = 'partner'):
        self.partner = partner
        self.limits = limits
        self.hold_over_slices = bool(hold_over_slices)
        self.detail = detail
        self.takes_time = bool(getattr(partner, 'takes_time', False))
        self.dof, self.involved, self.subtasks = 'rotation', False, []
        self._held = 0.0

    @property
    def answers_states(self) -> bool:
        """Return True while the partner answers states (while involved)."""
        return self.involved

    def on_session(self, dof: str, involved: bool, subtasks) -> None:
        """Take the roles a session announces."""
        self.dof, self.involved, self.subtasks = dof, bool(involved), list(subtasks)

    def start_episode(self, episode: int) -> None:
        """Tell the partner the episode about to start (if it listens)."""
        if hasattr(self.partner, 'start_episode'):
            self.partner.start_episode(int(episode))

    def answer(self, episode: int, state, stamp_ns: int, slice_index: int = 0) -> HumanAnswer:
        """Return the partner's answer to a (slice) state."""
        if self.partner is None:
            command = 0.0
        elif slice_index and self.hold_over_slices:
            command = self._held
        elif self.takes_time:
            command = float(self.partner(state, self.subtasks, now=stamp_ns * 1e-9))
        else:
            command = float(self.partner(state, self.subtasks))
        self._held = command
        return HumanAnswer(command, command * self.limits.full_scale(self.dof), self.dof,
                           SOURCE_SIMULATED, self.detail, True)


class EpisodeLoop:
    """The task one control step per call (see the module docstring).

    ``stepper``: an ``hrc_sim_node.stepper.SimStepper`` (physics and step protocol; one for
    a session, so the stamps run on the session's clock); ``human``: a human side;
    ``on_slice(stamp, wrench)``: told each slice answer's wrench (the engine records it).
    """

    def __init__(self, stepper, human, on_slice=None):
        self.stepper = stepper
        self.human = human
        self.on_slice = on_slice
        self.episode = 0
        self.human_dof = 'rotation'
        self.advanced = None          # the newest Advanced (the period's state to answer)

    @classmethod
    def on_physics(cls, physics, human, robot_dof: str = 'rotation') -> 'EpisodeLoop':
        """Return the loop on ``physics`` (a SliderPendulumBall) in lockstep with both actors.

        The step protocol takes the physics' control period, limits and human period, as the
        sim node's own protocol in lockstep; ``robot_dof`` until :meth:`set_roles` says.
        """
        params = physics.params
        protocol = StepProtocol(ProtocolSettings(
            control_period=params.control_period, max_force=params.max_force,
            max_torque=params.max_torque, robot_dof=robot_dof, human_period=params.human_period))
        return cls(SimStepper(physics, protocol), human)

    @property
    def protocol(self):
        """Return the sim's step protocol (stamps, counters)."""
        return self.stepper.protocol

    def set_roles(self, robot_dof: str, human_dof: str, involved: bool, subtasks) -> None:
        """Announce the roles to the human and to the sim, as a SessionStatus does."""
        self.human_dof = human_dof
        self.human.on_session(human_dof, involved, list(subtasks))
        # whether the human is involved decides whether a period is stepped slice by slice
        self.stepper.protocol.set_roles(robot_dof, involved)

    def start(self, episode: int, seed=None):
        """Start ``episode`` from the physics seeded with ``seed``; return its first Advanced."""
        self.episode = int(episode)
        self.human.start_episode(self.episode)
        self.advanced = self.stepper.start_episode(self.episode, seed)
        return self.advanced

    def answer(self):
        """Return the human's answer to the period's state, or None while it sits out."""
        if not self.human.answers_states:
            return None
        advanced = self.advanced
        return self.human.answer(self.episode, advanced.state, advanced.stamp)

    def step(self, robot_wrench, answer):
        """Run the period with the robot's wrench and the human's answer; return the next state.

        ``answer``: :meth:`answer`'s (None while the human sits out).
        """
        human_wrench = wrench_on(answer.dof, answer.wrench) if answer is not None else None
        self.advanced = self.stepper.run_period(robot_wrench, human_wrench, self._answer_slice)
        return self.advanced

    def _answer_slice(self, middle):
        answer = self.human.answer(self.episode, middle.state, middle.stamp, middle.slice)
        wrench = wrench_on(answer.dof, answer.wrench)
        if self.on_slice is not None:
            self.on_slice(middle.stamp, wrench)
        return wrench


class LoopObserver:
    """What :func:`run_agent_session` tells as it goes; each method here does nothing.

    The engine records the graph's messages from these calls; the offline runner saves its
    checkpoints and reports its episodes.
    """

    def episode_starting(self, plan) -> None:
        """Hear that an episode begins (``plan``: the core's EpisodePlan; roles announced)."""

    def state(self, advanced) -> None:
        """Hear a period's state (an ``hrc_sim_node.stepper.Advanced``)."""

    def decided(self, advanced, decision, answer, robot_wrench) -> None:
        """Hear both actors' answers to ``advanced`` (``answer``: the human's, or None)."""

    def episode_finished(self, result) -> None:
        """Hear that the core ended an episode (``result``: its EpisodeResult)."""

    def updating(self, result) -> None:
        """Hear that the core is about to update its policy after ``result``'s episode."""

    def after_episode(self, result, update_stats) -> None:
        """Hear that the episode and its update (``update_stats``, or None) are done."""


def run_agent_episode(core, loop: EpisodeLoop, observer: LoopObserver = None):
    """Run one episode of ``core`` (an AgentCore) through ``loop``; return its EpisodeResult.

    Each control step as the lockstep graph takes it: both actors answer the period's state
    (the human only while it answers states); the human's answer goes to the core when it
    asks for the same step's (``needs_human_action``); then the period runs.
    """
    observer = observer or LoopObserver()
    plan = core.start_episode()
    loop.set_roles(core.robot_dof, core.human_dof, core.human_involved, core.human_subtasks)
    observer.episode_starting(plan)
    advanced = loop.start(plan.episode, plan.seed)
    observer.state(advanced)
    while not advanced.episode_over:
        answer = loop.answer()
        human_action = None
        if core.needs_human_action:
            human_action = answer.command if answer is not None else 0.0
        decision = core.act(advanced.observed, human_action)
        robot_wrench = wrench_on(core.robot_dof, decision.wrench)
        observer.decided(advanced, decision, answer, robot_wrench)
        advanced = loop.step(robot_wrench, answer)
        observer.state(advanced)
    result = core.end_episode(advanced.observed)
    observer.episode_finished(result)
    return result


def run_agent_session(core, loop: EpisodeLoop, observer: LoopObserver = None,
                      max_episodes=None) -> int:
    """Run ``core`` through ``loop`` until it is done (or ``max_episodes`` more); return them.

    After each episode the policy update when the core is due for one (phase ``updating``).
    """
    observer = observer or LoopObserver()
    episodes = 0
    while core.phase not in ('done', 'aborted') and (max_episodes is None
                                                      or episodes < max_episodes):
        result = run_agent_episode(core, loop, observer)
        episodes += 1
        stats = None
        if core.phase == 'updating':
            observer.updating(result)
            stats = core.update()
        observer.after_episode(result, stats)
    return episodes
