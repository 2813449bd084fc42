"""What the person at the joystick and the experimenter see: the data behind the pages.

Pure (no rclpy): the display node feeds :class:`DisplayModel` with what arrives on
``/hrc/state``, ``/hrc/session``, ``/hrc/episode`` and ``/hrc/human/action`` (converted to the
plain views below); the pages (``hrc_live/web``) draw the scene in the browser from the states
the node pushes, and show the words computed from a :class:`Snapshot` of the model:

* ``hrc_live.display_words``: :func:`~hrc_live.display_words.overlay`, the person's banner,
  panel lines, result box and countdown, one place, tested on its own; the numbering is the
  same everywhere (episode x of y, test episode k of n, episodes with you so far);
* ``hrc_live.display_documents``: the scene's geometry (the whole reachable configuration is
  always in the picture), the console's data (input source and health, the running episode's
  errors, the totals) and the other JSON documents; non-finite numbers never reach JSON.
"""

from dataclasses import dataclass, replace
import math
import threading
import typing

from hrc_common.contract import InputSource
from hrc_sim_node.physics import PhysicsParams

# HumanAction.SOURCE_* order.
SOURCE_NAMES = tuple(source.label for source in InputSource)


@dataclass(frozen=True)
class StateView:
    """What the display needs of a TaskState."""

    episode: int
    step: int
    slider_position: float      # S_x (m)
    pendulum_angle: float       # P_z (rad)
    ball_position: float        # B_y (m)
    final: bool                 # truncated or terminated: the episode is over
    slider_velocity: float = 0.0            # m/s
    pendulum_angular_velocity: float = 0.0  # rad/s
    ball_velocity: float = 0.0              # m/s
    human_command_missing: bool = False
    robot_command_missing: bool = False

    def finite(self) -> bool:
        """Return whether every number of the state is finite."""
        return all(math.isfinite(value) for value in (
            self.slider_position, self.pendulum_angle, self.ball_position,
            self.slider_velocity, self.pendulum_angular_velocity, self.ball_velocity))


@dataclass(frozen=True)
class SessionView:
    """What the display needs of a SessionStatus."""

    session_id: str
    case_id: int
    strategy: str
    training_step: int
    training_step_count: int
    human_dof: str
    human_involved: bool
    human_subtasks: tuple
    episode: int
    total_episodes: int
    human_involved_episodes: int
    phase: str
    message: str = ''


@dataclass(frozen=True)
class ResultView:
    """What the display needs of an EpisodeSummary."""

    episode: int
    evaluation: bool
    human_involved: bool
    slider_error: float         # m
    pendulum_error: float       # rad
    ball_error: float           # m
    total_error: float
    converged: bool


@dataclass(frozen=True)
class HumanView:
    """The newest HumanAction: where the human's command comes from."""

    source: str                 # one of SOURCE_NAMES
    detail: str                 # e.g. the device path, or why the input is lost
    engaged: bool
    command: float              # normalized [-1, 1]
    received: float             # monotonic s


@dataclass(frozen=True)
class AgentPlan:
    """The agent's parameters the overlay uses (asked from the agent node)."""

    max_training_episodes: int
    evaluation_episodes: int
    episode_break: float        # s between episodes (realtime), 0 in lockstep


@dataclass(frozen=True)
class AloneRun:
    """The robot practising alone before the person joins (lockstep, no wall time waited).

    Its episodes are the session's training episodes without the person (the agent's own
    counters, so a pause or a restarted agent does not start the count again); its time leaves
    out the pauses.
    """

    started: float              # monotonic s of the first status without the human
    first_episode: int          # training episodes done when it started (kept for the rate)
    ended: typing.Optional[float] = None   # monotonic s the human joined
    episodes: int = 0           # training episodes practised alone
    paused_since: typing.Optional[float] = None    # monotonic s a pause began (None: running)
    paused_total: float = 0.0   # s paused so far

    def seconds(self, now: float) -> float:
        """Return the seconds practised alone (pauses left out)."""
        end = self.ended if self.ended is not None else now
        paused = self.paused_total + (end - self.paused_since if self.paused_since is not None
                                      else 0.0)
        return max(0.0, end - self.started - paused)

    def words(self, now: float, unit: str = 'episode') -> str:
        """Return "the robot practised alone: N episodes in T s" (``unit`` 'round': the page)."""
        verb = 'practised' if self.ended is not None else 'is practising'
        return (f'The robot {verb} alone: {self.episodes} {unit}'
                f'{"s" if self.episodes != 1 else ""} in {self.seconds(now):.0f} s.')

    def wait_estimate(self, now: float, cap: typing.Optional[int],
                      done: int) -> typing.Optional[float]:
        """Return at most how many more seconds the robot practises alone (None: unknown).

        An upper bound: the rate so far times the training episodes left under the cap
        (``max_training_episodes``); it may converge, and the person join, sooner.
        """
        practised = done - self.first_episode
        if cap is None or practised <= 0 or self.ended is not None or done >= cap:
            return None
        return (cap - done) * self.seconds(now) / practised


@dataclass(frozen=True)
class EpisodeErrors:
    """Running mean absolute errors of the current episode (from its states)."""

    episode: int = -1
    steps: int = 0
    last_step: int = -1         # the newest state's step (a smaller one: the episode restarted)
    slider: float = 0.0         # sum |S_x| (m)
    pendulum: float = 0.0       # sum |P_z| (rad)
    ball: float = 0.0           # sum |B_y| (m)
    human_missing: int = 0      # states whose human command did not arrive in time
    robot_missing: int = 0

    def add(self, state: StateView) -> 'EpisodeErrors':
        """Return the errors with ``state`` added.

        A new episode starts them again, and so does an attempt of the same episode run again
        after an interruption (its step goes back): the numbers are the current attempt's.
        """
        restarted = state.episode == self.episode and state.step <= self.last_step
        base = (self if state.episode == self.episode and not restarted
                else EpisodeErrors(episode=state.episode))
        if not state.finite():
            return base
        return replace(base, steps=base.steps + 1, last_step=state.step,
                       slider=base.slider + abs(state.slider_position),
                       pendulum=base.pendulum + abs(state.pendulum_angle),
                       ball=base.ball + abs(state.ball_position),
                       human_missing=base.human_missing + state.human_command_missing,
                       robot_missing=base.robot_missing + state.robot_command_missing)

    def means(self) -> dict:
        """Return the mean errors so far (m, rad, m), 0 before the first state."""
        steps = max(self.steps, 1)
        return {'slider': self.slider / steps, 'pendulum': self.pendulum / steps,
                'ball': self.ball / steps}


@dataclass(frozen=True)
class Snapshot:
    """Everything the pages show, at one instant (monotonic s ``now``)."""

    now: float
    physics: PhysicsParams
    state: typing.Optional[StateView] = None
    invalid_state: bool = False     # the newest state had a non-finite number
    session: typing.Optional[SessionView] = None
    result: typing.Optional[ResultView] = None
    previous_result: typing.Optional[ResultView] = None
    plan: typing.Optional[AgentPlan] = None
    break_started: typing.Optional[float] = None    # monotonic s the current break began
    result_time: typing.Optional[float] = None      # monotonic s the last result arrived
    episode_started: typing.Optional[float] = None  # monotonic s step 0 of the episode arrived
    geometry_from_sim: bool = False
    human: typing.Optional[HumanView] = None
    errors: EpisodeErrors = EpisodeErrors()
    alone: typing.Optional[AloneRun] = None
    evaluation_with_human: frozenset = frozenset()  # evaluation episodes the person played
    evaluation_done: int = 0                        # evaluation episodes finished
    session_started: typing.Optional[float] = None  # monotonic s of the first status
    input_lost: str = ''        # why the person's input is lost ('' = it is not)
    last_training_converged: typing.Optional[bool] = None   # of the newest training result
    # the running episode was stopped (pause, abort, lost input): it does not run again until
    # a new first state (step 0) comes, so the countdown of the resume shows meanwhile
    interrupted: bool = False
    # the person has played (part of) a round of this session: after a resume mid-round the
    # next one is not "your first"
    person_played: bool = False
    replay: str = ''            # what a replay node replays ('' = a live session)
    runner_waiting: str = ''    # why the session runner waits before starting ('' = it does not)
    # each node's newest status on /diagnostics: (name, level 0..3, message, monotonic s)
    health: tuple = ()


@dataclass(frozen=True)
class Overlay:
    """The words of the person's page at one instant."""

    banner: str
    tone: str                   # act | wait | stop | info
    lines: tuple                # the panel's lines
    result: tuple = ()          # the result box's lines (empty: no box)
    countdown: typing.Optional[int] = None  # whole seconds to the next episode, if known
    episode_label: str = ''
    notice: str = ''            # a problem the person must know about (shown over the scene)


class DisplayModel:
    """The newest state, session, results, human input and parameters, shared between threads.

    The ROS executor thread calls the ``on_*`` methods; the HTTP threads call :meth:`snapshot`.
    ``now`` is monotonic seconds, passed in so that tests control time.
    """

    def __init__(self, physics: PhysicsParams = None):
        self._lock = threading.Lock()
        self._snapshot = Snapshot(now=0.0, physics=physics or PhysicsParams())
        self.version = 0            # increases with every change

    def _update(self, **changes) -> None:
        self._snapshot = replace(self._snapshot, **changes)
        self.version += 1

    def on_state(self, state: StateView, now: float) -> None:
        """Take a new state; step 0 starts an episode, a final state starts the break.

        A state with a non-finite number is not kept (the picture stays at the last good
        one) and raises the invalid-state notice until a finite state comes.
        """
        with self._lock:
            if not state.finite():
                self._update(invalid_state=True)
                return
            previous = self._snapshot.state
            changes = {'state': state, 'invalid_state': False,
                       'errors': self._snapshot.errors.add(state)}
            if state.step == 0 or previous is None or previous.episode != state.episode:
                changes['episode_started'] = now
            if state.step == 0:
                changes['interrupted'] = False
            session = self._snapshot.session
            if (state.step > 0 and session is not None and session.human_involved
                    and state.episode >= session.episode):
                changes['person_played'] = True
            if state.final and not (previous is not None and previous.final
                                    and previous.episode == state.episode):
                changes['break_started'] = now
            self._update(**changes)

    def on_session(self, session: SessionView, now: float) -> None:
        """Take a new session status; a resume restarts the break (the agent waits again)."""
        with self._lock:
            current = self._snapshot
            previous = current.session
            changes = {'session': session}
            if previous is not None and previous.session_id != session.session_id:
                changes.update(plan=None, alone=None, evaluation_with_human=frozenset(),
                               evaluation_done=0, session_started=now, person_played=False)
                current = replace(current, alone=None)
            if current.session_started is None:
                changes['session_started'] = now
            if previous is not None and previous.phase == 'paused' and session.phase != 'paused':
                changes['break_started'] = now
            if session.phase in ('paused', 'aborted'):
                changes['interrupted'] = True
            alone = current.alone
            # the robot's own episodes: every training episode so far without the person (the
            # agent's counters: a pause or a restarted agent does not start the count again)
            robot_own = session.total_episodes - session.human_involved_episodes
            if not session.human_involved and session.phase in ('training', 'updating'):
                if alone is None or alone.ended is not None:
                    alone = AloneRun(started=now, first_episode=session.total_episodes)
                if alone.paused_since is not None:
                    alone = replace(alone, paused_total=alone.paused_total + now
                                    - alone.paused_since, paused_since=None)
                changes['alone'] = replace(alone, episodes=robot_own)
            elif alone is not None and alone.ended is None:
                if session.phase in ('paused', 'aborted') and not session.human_involved:
                    if alone.paused_since is None:     # a pause: the run goes on after it
                        changes['alone'] = replace(alone, paused_since=now)
                else:
                    changes['alone'] = replace(alone, ended=now, episodes=robot_own)
            self._update(**changes)

    def on_result(self, result: ResultView, now: float) -> None:
        """Take the summary of a finished episode (repeats of the same one are ignored)."""
        with self._lock:
            current = self._snapshot.result
            if current is not None and current.episode == result.episode:
                return
            changes = {'result': result, 'previous_result': current, 'result_time': now}
            if not result.evaluation:
                changes['last_training_converged'] = result.converged
            if result.evaluation:
                changes['evaluation_done'] = self._snapshot.evaluation_done + 1
                if result.human_involved:
                    changes['evaluation_with_human'] = (
                        self._snapshot.evaluation_with_human | {result.episode})
            self._update(**changes)

    def on_human(self, human: HumanView) -> None:
        """Take the newest human action's source."""
        with self._lock:
            self._update(human=human)

    def set_input_lost(self, reason: str) -> None:
        """Set (or clear, with '') the reason the person's input is lost."""
        with self._lock:
            if reason != self._snapshot.input_lost:
                self._update(input_lost=reason,
                             interrupted=self._snapshot.interrupted or bool(reason))

    def set_replay(self, source: str) -> None:
        """Set (or clear, with '') what a replay node replays."""
        with self._lock:
            self._update(replay=source)

    def set_health(self, name: str, level: int, message: str, now: float) -> None:
        """Take a node's status from /diagnostics (the newest of each name is kept)."""
        with self._lock:
            kept = {item[0]: item for item in self._snapshot.health}
            kept[name] = (name, int(level), message, now)
            self._update(health=tuple(sorted(kept.values())))

    def set_runner_waiting(self, reason: str) -> None:
        """Set (or clear, with '') why the session runner waits before it starts the nodes."""
        with self._lock:
            self._update(runner_waiting=reason)

    def set_plan(self, plan: typing.Optional[AgentPlan]) -> None:
        """Set what the agent's parameters say (episodes, break)."""
        with self._lock:
            self._update(plan=plan)

    def set_physics(self, physics: PhysicsParams) -> None:
        """Set the sim's geometry and timing (from the sim's parameters)."""
        with self._lock:
            self._update(physics=physics, geometry_from_sim=True)

    def snapshot(self, now: float) -> Snapshot:
        """Return a consistent copy of everything, at ``now``."""
        with self._lock:
            return replace(self._snapshot, now=now)

    @property
    def plan(self) -> typing.Optional[AgentPlan]:
        """Return the agent's plan, if known."""
        with self._lock:
            return self._snapshot.plan


# ---------------------------------------------------------------------------- geometry


# ---------------------------------------------------------------------------- documents


