"""A whole headless hrc session in one process, from the same pure cores as the nodes.

The graph runs four processes talking over DDS; the engine calls the same cores directly, in
the order the lockstep graph makes them act, and writes the same bags:

* sim: :class:`~hrc_sim_node.physics.SliderPendulumBall` and the step protocol
  :class:`~hrc_sim_node.protocol.StepProtocol` (stamps, command reading and clamping, per-DOF
  dispatch, counters), with the sim's parameters;
* agent: :class:`~hrc_agent_node.agent_core.AgentCore` (strategy steps, PPO, evaluation) with
  the agent's parameters, checkpoints as the agent node writes them;
* human: the simulated human (``hrc_joystick_node.sim_human``) answering each state as the
  human node does with ``input: sim``;
* recording: one MCAP file per episode, ``metadata.yaml``, the ``hrc_session`` record, QoS
  metadata and type hashes (``hrc_bag.session_writer``), so ``hrc_report`` and rosbags read
  the bags of both engines alike.

For the same parameters and seed, the states, actions and rewards equal those of the graph in
lockstep (test/test_engine_equivalence.py). What differs: log and SessionStatus times are the
engine's wall clock, and nothing waits (no lockstep timeout can fire, nothing is missing).

API (picklable, for Ray or a process pool)::

    from hrc_common.session_plan import SessionSettings
    from hrc_engine.engine import EngineConfig, run_session
    result = run_session(EngineConfig(SessionSettings(case=2, seed=0, training_episodes=30,
                                                      bags_dir='bags', runs_dir='runs')))
    result.evaluation['total_error'], result.bag_dir
"""

from dataclasses import asdict, dataclass, field, replace
import os
import pathlib
import time
import typing

from hrc_common import bounded_yaml

from hrc_agent_node.agent_core import AgentCore, PopulationStepRefused
from hrc_agent_node.checkpoint import load_session_start, save_checkpoint
from hrc_agent_node.config import AgentParams
from hrc_bag.format import contract_description
from hrc_bag.session_writer import SessionWriter, TOPIC_TYPES
from hrc_common import qos_table, topics
from hrc_common.contract import Phase, SimLimits
from hrc_common.params import from_dict
from hrc_common.paths import params_dir as default_params_dir
from hrc_common.episode_numbers import episode_number
from hrc_common.session_control import FINAL_CHECKPOINT, LATEST_CHECKPOINT
from hrc_common.session_plan import compose, new_session_id, SessionSettings, write_session_files
from hrc_engine import messages
from hrc_engine.human import SimulatedHumanSide
from hrc_engine.loop import EpisodeLoop, run_agent_session
from hrc_sim_node.body_geometry import model_urdf
from hrc_sim_node.commands import ACTORS
from hrc_sim_node.physics import physics_params_of, SliderPendulumBall
from hrc_sim_node.protocol import ProtocolSettings, StepProtocol
from hrc_sim_node.sim_params import LOCKSTEP, SimParams
from hrc_sim_node.stepper import SimStepper

# The QoS each publisher of the graph offers, as (reliable, transient_local, deadline ns).
OFFERED_QOS = {topic: (qos.reliable, qos.transient_local, qos.deadline_ns)
               for topic, qos in qos_table.OF_TOPIC.items()}


@dataclass
class EngineConfig:
    """One session to run in process: the session's settings and the engine's own run options.

    What the session is (case, seed, episodes, folders, human, overrides, ...) is the one
    session configuration, :class:`hrc_common.session_plan.SessionSettings`, as ``hrc session``
    builds it; the fields beside it are how this engine runs it. Plain values, picklable.
    The engine runs lockstep only: ``settings.mode`` must be 'lockstep'.
    """

    settings: SessionSettings = field(default_factory=SessionSettings)
    checkpoints: bool = True            # write latest.pt after each episode, final.pt
    params_dir: str = ''                # '' = hrc_common.paths.params_dir()
    parameters: typing.Optional[dict] = None  # composed {node: {...}}; None = compose here
    quiet: bool = True                  # False: one line per episode on stdout


@dataclass
class SessionResult:
    """What a session produced (plain values, picklable)."""

    session_id: str
    case: int
    seed: int
    strategy: str
    training_episodes: int
    human_involved_episodes: int
    converged: bool
    evaluation: dict                    # Table II metrics over the evaluation episodes
    episodes: list                      # one dict per episode (EpisodeSummary fields)
    steps: int                          # control steps run
    wall_seconds: float
    bag_dir: str = ''                   # '' when not recorded
    run_dir: str = ''
    counters: dict = field(default_factory=dict)  # the sim's command events (all zero here)
    episode_seconds: list = field(default_factory=list)  # wall s of each episode's steps


def compose_parameters(config: EngineConfig) -> tuple:
    """Return (SessionSettings, {node: parameters}) exactly as ``session`` composes them.

    The settings returned are a copy of ``config.settings`` with the session id filled in.
    """
    settings = replace(config.settings, overrides=dict(config.settings.overrides))
    if settings.mode != 'lockstep':
        raise ValueError(f'mode {settings.mode!r}: the in-process engine runs lockstep only; '
                         'use --engine graph')
    if not settings.session_id:
        settings.session_id = new_session_id(settings)
    params_dir = pathlib.Path(config.params_dir) if config.params_dir else default_params_dir()
    parameters = config.parameters or compose(settings, params_dir)
    return settings, parameters


def topic_descriptions() -> dict:
    """Return {topic: TopicDescription} as the graph's publishers offer them (no rclpy)."""
    return {topic: contract_description(TOPIC_TYPES[topic], *OFFERED_QOS[topic])
            for topic in OFFERED_QOS}


class WallClock:
    """Strictly increasing wall time (ns since the epoch) for log times."""

    def __init__(self):
        self._last = 0

    def __call__(self) -> int:
        self._last = max(self._last + 1, time.time_ns())
        return self._last


class InProcessSession:
    """One session: the cores wired as the lockstep graph wires the nodes."""

    def __init__(self, config: EngineConfig):
        self.config = config
        self.settings, self.parameters = compose_parameters(config)
        self.session_id = self.settings.session_id
        sim_values = dict(self.parameters['sim'], mode=LOCKSTEP)
        self.sim_params = from_dict(SimParams, sim_values)
        if sorted(self.sim_params.expected_actors) != sorted(ACTORS):
            # The engine steps when the robot has answered and the human too while involved,
            # as the graph's sim does with both actors expected; with one actor expected the
            # graph's sim steps on that actor's command alone and takes the other's only if it
            # came first, a race the engine cannot reproduce.
            raise ValueError(f'sim.expected_actors {list(self.sim_params.expected_actors)}: '
                             f'the in-process engine waits for both actors '
                             f'({", ".join(ACTORS)}), as the lockstep graph does by default; '
                             'use --engine graph for other settings')
        self.agent_params = from_dict(AgentParams, self.parameters['agent'])
        self.physics = SliderPendulumBall(physics_params_of(self.sim_params))
        self.protocol = StepProtocol(ProtocolSettings.of(self.sim_params))
        self.stepper = SimStepper(self.physics, self.protocol)
        # What the sim owns, passed as the graph passes it (the reset response, the sim's
        # parameters): the physics' control period and limits.
        self.limits = SimLimits.of(self.sim_params)
        self.core = AgentCore(self.agent_params, limits=self.limits)
        load_session_start(self.core)
        case = self.core.case
        if (case.has_population_steps and not self.core.population_partner
                and self.core.phase == Phase.TRAINING
                and self.core.training_step.index < case.first_person_step):
            # Partners first before its pre-training: refused now (exit 2), not after minutes
            # of the robot alone; the engine cannot pre-train (hrc_partners is a higher layer).
            raise PopulationStepRefused(
                f'case {case.case_id}: the steps before the person train with a simulated '
                'population, which this engine cannot run: start from the pre-trained '
                f'checkpoint (python -m hrc_partners.partners_first --case {case.case_id}, '
                'then --resume-from), or use hrc experiment / hrc session (graph), which '
                'pre-train')
        self.human = SimulatedHumanSide.from_parameters(self.parameters['human'], self.limits)
        self.loop = EpisodeLoop(self.stepper, self.human, on_slice=self._slice_answered)
        self.clock = WallClock()
        self.run_dir = pathlib.Path(self.settings.runs_dir) / self.session_id
        checkpoint_root = self.agent_params.checkpoint_dir
        self.checkpoint_dir = (pathlib.Path(checkpoint_root) / self.core.session_id
                               if checkpoint_root and config.checkpoints else None)
        self.writer = None
        self.episodes = []
        self.episode_seconds = []        # wall s of each episode's steps (no update, no save)
        self.steps = 0
        self._stamps = {}                # step -> stamp (ns) of the running episode's states

    # -- recording --------------------------------------------------------------------------
    def _open_bags(self) -> None:
        _, config_path = write_session_files(self.settings, self.parameters, self.run_dir,
                                             self.config.params_dir or None)
        text = config_path.read_text()
        self.writer = SessionWriter(self.settings.bags_dir, self.session_id,
                                    session_config=bounded_yaml.load(text, str(config_path)),
                                    session_config_text=text,
                                    descriptions=topic_descriptions())
        self._write(topics.ROBOT_DESCRIPTION, {'data': model_urdf(self.physics.params)})

    def _write(self, topic: str, message: dict) -> None:
        if self.writer is not None:
            # as plain values: the writer encodes them (hrc_bag.serializer) and keeps the last
            # SessionStatus for the hrc_session record
            self.writer.write(topic, message, self.clock())

    def _announce(self, text: str) -> None:
        """Publish a SessionStatus as the agent does (and tell the human the roles)."""
        core = self.core
        # the human and the sim take the roles from the same announcement
        self.loop.set_roles(core.robot_dof, core.human_dof, core.human_involved,
                            core.human_subtasks)
        self._write('/hrc/session', messages.session_status(core, text, self.clock()))

    # -- the session ------------------------------------------------------------------------
    def run(self) -> SessionResult:
        """Run the session to its end (phase done); return its result."""
        started = time.perf_counter()
        if self.settings.record:
            self._open_bags()
        core = self.core
        try:
            self._announce('session starting: ' + core.status_line())
            run_agent_session(core, self.loop, self)
            summary = core.evaluation_summary()
            self._save_checkpoint(FINAL_CHECKPOINT)
            self._announce('session done: ' + core.status_line())
        finally:
            if self.writer is not None:
                self.writer.close()
            self.physics.close()
        return SessionResult(
            self.session_id, core.case_id, self.agent_params.seed, core.strategy,
            core.total_episodes, core.human_involved_episodes, bool(core.converged),
            summary, self.episodes, self.steps, time.perf_counter() - started,
            str(pathlib.Path(self.settings.bags_dir) / self.session_id)
            if self.writer is not None else '', str(self.run_dir),
            dict(self.protocol.totals), self.episode_seconds)

    # -- what the loop tells (hrc_engine.loop.LoopObserver): the graph's messages ----------
    def episode_starting(self, plan) -> None:
        """Announce the episode; open its bag (the loop has given the roles)."""
        self._episode_started = time.perf_counter()
        evaluation = '(evaluation)' if plan.evaluation else ''
        self._announce(f'episode {episode_number(plan.episode)} {evaluation} starting: '
                       + self.core.status_line())
        if self.writer is not None:
            self.writer.begin_episode(plan.episode)

    def state(self, advanced) -> None:
        """Write the state of a control step (an hrc_sim_node.stepper.Advanced)."""
        self._stamps[advanced.state.step] = advanced.stamp
        self._write('/hrc/state', messages.task_state(
            advanced.state, self.protocol.episode, advanced.stamp, advanced.missing,
            human_applied=advanced.human_applied))
        self._write(topics.JOINT_STATES, messages.joint_state(advanced.state, advanced.stamp))
        if advanced.state.step:
            self.steps += 1        # a control step ran
        if advanced.episode_over:
            self.episode_seconds.append(time.perf_counter() - self._episode_started)

    def decided(self, advanced, decision, answer, robot_wrench) -> None:
        """Write both actors' answers to a state, as the agent and the human node publish."""
        stamp = advanced.stamp
        self._write('/hrc/robot/cmd_wrench', messages.wrench_stamped(stamp, robot_wrench))
        if decision.previous is not None:
            self._write_step(decision.previous)
        if answer is not None:
            self._write('/hrc/human/action', messages.human_action(
                stamp, self.loop.episode, advanced.state.step, answer))
            self._write('/hrc/human/cmd_wrench', messages.wrench_stamped(
                stamp, messages.wrench_on(answer.dof, answer.wrench)))

    def _slice_answered(self, stamp: int, wrench) -> None:
        """Write the human's wrench answering a slice state (only that, as the node does)."""
        self._write('/hrc/human/cmd_wrench', messages.wrench_stamped(stamp, wrench))

    def _write_step(self, record) -> None:
        self._write('/hrc/agent/step', messages.agent_step(record, self._stamps[record.step]))

    def episode_finished(self, result) -> None:
        """Write the episode's last step and its summary."""
        if result.last_record is not None:
            self._write_step(result.last_record)
        summary = messages.episode_summary(self.core, result, self.loop.advanced.stamp)
        self._write('/hrc/episode', summary)
        self.episodes.append({key: value for key, value in summary.items() if key != 'header'})
        if not self.config.quiet:
            kind = ' (evaluation)' if result.evaluation else ''
            print(f'[engine] episode {episode_number(result.episode)}{kind}: return '
                  f'{result.episode_return:.2f}, total error '
                  f'{result.total_error:.4f}{", converged" if result.converged else ""}',
                  flush=True)

    def updating(self, result) -> None:
        """Announce the policy update, as the agent does before it."""
        self._announce(f'updating the policy after episode '
                       f'{episode_number(result.episode)} '
                       f'({self.core.buffered_samples} samples)')

    def after_episode(self, result, update_stats) -> None:
        """Save the latest checkpoint, announce, close the episode's bag."""
        core = self.core
        self._save_checkpoint(LATEST_CHECKPOINT)
        if core.phase != 'done':
            self._announce(core.status_line())
        if self.writer is not None:
            # The recorder closes an episode's file close_grace after its summary; here it
            # closes at once, after the SessionStatus that follows the episode.
            self.writer.end_episode()
        self._stamps = {}

    def _save_checkpoint(self, name: str) -> None:
        if self.checkpoint_dir is None:
            return
        save_checkpoint(self.core, os.path.join(self.checkpoint_dir, name))


def run_session(config: EngineConfig) -> SessionResult:
    """Run one session in this process (see the module docstring); return its result."""
    return InProcessSession(config).run()


def config_dict(config: EngineConfig) -> dict:
    """Return the config as plain values (for logs and experiment tables)."""
    return asdict(config)


class SummariesSession(InProcessSession):
    """A session that also keeps every EpisodeSummary it writes, as plain values (``summaries``).

    For benches and tests that read a session's episodes without its bags (``record=False``).
    """

    def __init__(self, config: EngineConfig):
        super().__init__(config)
        self.summaries = []

    def _write(self, topic: str, message: dict) -> None:
        super()._write(topic, message)
        if topic == '/hrc/episode':
            self.summaries.append(message)
