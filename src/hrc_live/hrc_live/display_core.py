"""What the person at the joystick and the experimenter see: the words and the data of the pages.

Pure (no rclpy): the display node feeds :class:`DisplayModel` with what arrives on
``/hrc/state``, ``/hrc/session``, ``/hrc/episode`` and ``/hrc/human/action`` (converted to the
plain views below); the pages (``hrc_live/web``) draw the scene in the browser from the states
the node pushes, and show the words computed here:

* :func:`overlay`: the person's banner, panel lines, result box and countdown, one place,
  tested on its own; the numbering is the same everywhere (episode x of y, test episode k of n,
  episodes with you so far);
* :func:`scene_geometry`: the sim's geometry and the world box the page fits to the window, so
  that the whole reachable configuration (beam at either hinge stop, ball at either end stop,
  slider at either end of the rod) is always in the picture;
* :func:`console_document`: what the experimenter's console shows (input source and health,
  the running episode's errors, the totals).

Non-finite numbers never reach JSON: a state with one is replaced by a notice
(:func:`state_document`).
"""

from dataclasses import dataclass, replace
import math
import re
import threading
import typing

from hrc_common.contract import BODY_COLOURS, InputSource, rgb8
from hrc_sim_node.physics import (BEAM_HEIGHT, body_poses, PhysicsParams, PhysicsState,
                                  ROD_RADIUS, SLIDER_SIZE)
# HumanAction.SOURCE_* order.
SOURCE_NAMES = tuple(source.label for source in InputSource)

# The bodies' colours (hrc_common.contract, as the sim draws them) as 8-bit RGB, and the page's.
COLORS = {**{name: rgb8(colour) for name, colour in BODY_COLOURS.items()},
          'background': (242, 243, 245), 'target': (200, 204, 210)}

# What each subtask asks of the person, and what each degree of freedom gives them.
SUBTASK_WORDS = {'slider': 'keep the slider in the middle of the rod',
                 'pendulum': 'keep the pendulum level',
                 'ball': 'keep the ball in the middle of the pendulum'}
CONTROL_WORDS = {'translation': 'You move the slider up and down (stick up = up).',
                 'rotation': 'You tilt the pendulum (stick up = right end up).'}
# A human command older than this (s) counts as stale on the console.
STALE_COMMAND_S = 1.0
INVALID_STATE_NOTICE = ('The simulation sent an invalid state (not a finite number): the '
                        'picture is frozen. Operator: see the sim log.')
# What the person reads when their joystick is lost (the technical reason is on the console).
INPUT_LOST_BANNER = 'The joystick is disconnected: paused. Please wait for the operator.'
INPUT_LOST_NOTICE = ('The joystick is disconnected. Please let go of it and wait: the operator '
                     'will reconnect it and resume.')


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

    def words(self, now: float) -> str:
        """Return "the robot practised alone: N episodes in T s"."""
        verb = 'practised' if self.ended is not None else 'is practising'
        return (f'The robot {verb} alone: {self.episodes} episode'
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
    slider: float = 0.0         # sum |S_x| (m)
    pendulum: float = 0.0       # sum |P_z| (rad)
    ball: float = 0.0           # sum |B_y| (m)
    human_missing: int = 0      # states whose human command did not arrive in time
    robot_missing: int = 0

    def add(self, state: StateView) -> 'EpisodeErrors':
        """Return the errors with ``state`` added (a new episode starts them again)."""
        base = self if state.episode == self.episode else EpisodeErrors(episode=state.episode)
        if not state.finite():
            return base
        return replace(base, steps=base.steps + 1,
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


def is_evaluating(session: SessionView, plan: typing.Optional[AgentPlan]) -> bool:
    """Return whether the current (or next) episode is a test (evaluation) episode."""
    if session.phase == 'evaluation':
        return True
    return (session.phase in ('paused', 'aborted', 'updating') and plan is not None
            and session.total_episodes < session.episode)


def episode_label(session: SessionView, plan: typing.Optional[AgentPlan]) -> str:
    """Return "Episode x of y" (or "Test episode k of n") for the current or next episode.

    Training episode x is ``total_episodes + 1``; test episode k counts from the first
    evaluation episode, whose index is the number of training episodes. The result box uses
    the same numbers (:func:`result_number`).
    """
    if session.strategy == 'practice':
        # the runner's practice: "practice: episode k of n, ..." in its message
        planned = re.search(r'episode \d+ of (\d+)', session.message)
        count = int(planned.group(1)) if planned else None
        number = session.total_episodes + 1 if count is None else min(
            session.total_episodes + 1, count)
        if count is not None and session.total_episodes >= count:
            return f'Practice: {count} episodes done'
        return f'Practice episode {number}' + (f' of {count}' if count else '')
    if session.phase == 'done':
        return f'{session.total_episodes} training episodes done'
    if is_evaluating(session, plan):
        index = session.episode - session.total_episodes + 1
        if plan is not None:    # never "3 of 2": a counter stays within its maximum
            index = min(index, plan.evaluation_episodes)
        total = f' of {plan.evaluation_episodes}' if plan is not None else ''
        return f'Test episode {max(index, 1)}{total}'
    number = session.total_episodes + 1
    if plan is not None:
        number = min(number, plan.max_training_episodes)
    total = f' of at most {plan.max_training_episodes}' if plan is not None else ''
    return f'Episode {number}{total}'


def result_number(result: ResultView, session: typing.Optional[SessionView]) -> str:
    """Return "Episode x" or "Test episode k" of a finished episode, numbered as the label."""
    if not result.evaluation:
        return f'Episode {result.episode + 1}'
    training = session.total_episodes if session is not None else 0
    return f'Test episode {result.episode - training + 1}'


def result_lines(result: ResultView, previous: typing.Optional[ResultView],
                 session: typing.Optional[SessionView] = None) -> tuple:
    """Return the short result of an episode, in the person's terms."""
    lines = [f'{result_number(result, session)} done',
             f'ball off centre: {100 * result.ball_error:.1f} cm on average',
             f'pendulum tilt: {math.degrees(result.pendulum_error):.1f} deg, '
             f'slider: {100 * result.slider_error:.1f} cm']
    if previous is not None and previous.total_error > 0 and (
            previous.evaluation == result.evaluation):
        change = (result.total_error - previous.total_error) / previous.total_error
        if change < -0.05:
            lines.append('Better than the episode before.')
        elif change > 0.05:
            lines.append('Not as good as the episode before.')
        else:
            lines.append('About as good as the episode before.')
    if result.converged:
        lines.append('Goal reached for this training step.')
    return tuple(lines)


def episodes_with_person(snapshot: Snapshot) -> int:
    """Return the episodes the person has played so far: training and test."""
    training = snapshot.session.human_involved_episodes if snapshot.session else 0
    return training + len(snapshot.evaluation_with_human)


def countdown_of(snapshot: Snapshot, in_episode: bool) -> typing.Optional[int]:
    """Return the whole seconds until the next episode starts, if known."""
    session, plan = snapshot.session, snapshot.plan
    if (in_episode or plan is None or plan.episode_break <= 0 or snapshot.break_started is None
            or session.phase not in ('training', 'updating', 'evaluation')):
        return None
    return max(0, math.ceil(snapshot.break_started + plan.episode_break - snapshot.now))


def overlay(snapshot: Snapshot, result_seconds: float = 5.0) -> Overlay:
    """Return the banner, panel lines, result box and countdown of ``snapshot``."""
    session, state, now = snapshot.session, snapshot.state, snapshot.now
    notice = INVALID_STATE_NOTICE if snapshot.invalid_state else ''
    if snapshot.input_lost:
        notice = INPUT_LOST_NOTICE      # the person needs no device path or FIFO detail
    if session is None:
        return Overlay('Please wait: the session is starting', 'info',
                       ('Waiting for the robot to announce the session.',), notice=notice)
    label = episode_label(session, snapshot.plan)
    lines = [label]
    if session.training_step_count > 1:
        lines.append(f'Training step {session.training_step + 1} of '
                     f'{session.training_step_count}')
    in_episode = (state is not None and not state.final and state.episode >= session.episode
                  and not snapshot.interrupted)
    if session.human_involved:
        lines.append(CONTROL_WORDS.get(session.human_dof, ''))
        tasks = [SUBTASK_WORDS.get(subtask, subtask) for subtask in session.human_subtasks]
        lines += [f'Your task: {task}.' for task in tasks]
    else:
        lines.append('The robot works alone in this step.')
    if snapshot.alone is not None and (snapshot.alone.episodes or snapshot.alone.ended is None):
        lines.append(snapshot.alone.words(now))
        wait = alone_wait(snapshot)
        if wait is not None:
            lines.append(f'You join in at most about {wait_words(wait)} (the robot may be '
                         f'ready sooner).')
    if in_episode and session.human_involved:   # lonely episodes run faster than the clock
        steps_left = max(0, snapshot.physics.steps_per_episode - state.step)
        lines.append(f'Time left: {steps_left * snapshot.physics.control_period:.0f} s')
    lines.append(f'Episodes with you so far: {episodes_with_person(snapshot)}')

    result = ()
    # The result stays up during the break and the first seconds of the next episode.
    showing_result = snapshot.result is not None and (
        not in_episode or (snapshot.episode_started is not None
                           and now - snapshot.episode_started < result_seconds))
    if showing_result:
        result = result_lines(snapshot.result, snapshot.previous_result, session)
    if snapshot.result is not None:
        lines.append(f'Last episode: ball {100 * snapshot.result.ball_error:.1f} cm off centre')

    countdown = countdown_of(snapshot, in_episode)
    phase = session.phase
    first_with_person = session.human_involved and episodes_with_person(snapshot) == 0
    if snapshot.input_lost:     # first: the runner stops the agent (phase aborted) for it
        banner, tone = INPUT_LOST_BANNER, 'stop'
    elif phase == 'aborted':
        banner, tone = 'Stopped by the operator. Please let go of the joystick.', 'stop'
    elif phase == 'done':
        banner, tone = 'The session is finished. Thank you!', 'info'
    elif phase == 'paused' and 'joystick disconnected' in session.message.lower():
        # the runner's pause for a lost input: the joystick is back, the operator resumes
        banner, tone = 'The joystick is connected again: please wait for the operator', 'wait'
    elif phase == 'paused':
        banner, tone = 'Paused by the operator: please wait', 'wait'
    elif not in_episode:
        if not session.human_involved:
            banner = 'The robot is learning alone, please wait'
            wait = alone_wait(snapshot)
            if wait is not None:
                banner += f' (at most about {wait_words(wait)})'
        elif phase == 'updating':
            banner = 'The robot is learning from the last episode: please wait'
        elif first_with_person and countdown:
            banner = f'Get ready: your first episode starts in {countdown} s'
        elif countdown:
            banner = f'Get ready: the next episode starts in {countdown} s'
        else:
            banner = 'The next episode is starting'
        tone = 'wait'
    elif not session.human_involved:
        banner, tone = 'The robot is learning alone, please wait', 'wait'
    else:
        tasks = [SUBTASK_WORDS.get(subtask, subtask) for subtask in session.human_subtasks]
        banner = ('Your turn: ' + ' and '.join(tasks)) if tasks else 'Your turn'
        tone = 'act'
    return Overlay(banner, tone, tuple(line for line in lines if line), result, countdown,
                   label, notice)


def alone_wait(snapshot: Snapshot) -> typing.Optional[float]:
    """Return at most how many more seconds the robot practises alone (None: unknown)."""
    alone, session, plan = snapshot.alone, snapshot.session, snapshot.plan
    if alone is None or alone.ended is not None or session is None or plan is None:
        return None
    return alone.wait_estimate(snapshot.now, plan.max_training_episodes,
                               session.total_episodes)


def wait_words(seconds: float) -> str:
    """Return a wait for a person: "40 s", "3 min" (rounded up)."""
    if seconds < 90:
        return f'{max(5, 5 * math.ceil(seconds / 5)):.0f} s'
    return f'{math.ceil(seconds / 60)} min'


def milestone(snapshot: Snapshot) -> str:
    """Return what the experimenter must know about the team now (the console's line).

    The robot alone (with the wait), "the person joins now" (the first 60 s after), or "the
    robot did not converge in N episodes" once training ended without it.
    """
    session, alone, now = snapshot.session, snapshot.alone, snapshot.now
    if session is None or session.strategy == 'practice':
        return ''
    cap = snapshot.plan.max_training_episodes if snapshot.plan is not None else None
    if session.phase in ('evaluation', 'done') and snapshot.last_training_converged is False:
        return (f'the robot did not converge in {session.total_episodes} episodes'
                + (f' (at most {cap})' if cap else '')
                + ('; the person never trained with it' if session.human_involved_episodes == 0
                   and session.human_subtasks else ''))
    if alone is not None and alone.ended is None:
        wait = alone_wait(snapshot)
        return (alone.words(now).rstrip('.') + (f'; the person joins in at most about '
                                                f'{wait_words(wait)}' if wait is not None
                                                else ''))
    if alone is not None and alone.ended is not None and now - alone.ended < 60.0:
        return (f'the person joins now, at episode {alone.first_episode + alone.episodes + 1} '
                f'({alone.words(now).rstrip(".").lower()})')
    return ''


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
                               evaluation_done=0, session_started=now)
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

def configuration_points(physics: PhysicsParams, slider: float, angle: float,
                         ball: float) -> list:
    """Return the outline points (world y, z in m) of every body in one configuration."""
    state = PhysicsState(step=0, time=0.0, slider_position=slider, slider_velocity=0.0,
                         pendulum_angle=angle, pendulum_angular_velocity=0.0,
                         ball_position=ball, ball_velocity=0.0, applied_force=0.0,
                         applied_torque=0.0, terminated=False, truncated=False)
    poses = body_poses(state, physics)
    cos_a, sin_a = math.cos(angle), math.sin(angle)
    half_beam = BEAM_HEIGHT / 2
    points = []
    # The beam's four corners, from the hinge to the east end.
    for along in (0.0, physics.pendulum_length):
        for across in (-half_beam, half_beam):
            points.append((along * cos_a - across * sin_a, slider + along * sin_a
                           + across * cos_a))
    ball_y, ball_z = poses['ball'][0][1], poses['ball'][0][2]
    radius = physics.ball_radius
    points += [(ball_y + dy, ball_z + dz) for dy, dz in ((radius, 0), (-radius, 0),
                                                         (0, radius), (0, -radius))]
    half_w, half_h = SLIDER_SIZE[1] / 2, SLIDER_SIZE[2] / 2
    points += [(dy, slider + dz) for dy in (-half_w, half_w) for dz in (-half_h, half_h)]
    return points


def scene_bounds(physics: PhysicsParams, margin: float = 0.03) -> dict:
    """Return the world box (m) holding every reachable configuration, plus ``margin``.

    Reachable: the slider anywhere on the rod, the beam anywhere between its hinge stops
    (+-``pendulum_limit``), the ball anywhere between its end stops; the extremes are taken
    over a fine grid of angles (the box of a rotating beam is not at the stops only).
    """
    half_rod = physics.rod_length / 2 + 0.02     # the rod reaches 2 cm beyond the slider stops
    ys, zs = [-ROD_RADIUS, ROD_RADIUS], [-half_rod, half_rod]
    limit = physics.pendulum_limit
    half_travel = physics.pendulum_length / 2
    for index in range(181):
        angle = -limit + 2 * limit * index / 180
        for slider in (-physics.rod_length / 2, physics.rod_length / 2):
            for ball in (-half_travel, half_travel):
                for y, z in configuration_points(physics, slider, angle, ball):
                    ys.append(y)
                    zs.append(z)
    return {'y_min': min(ys) - margin, 'y_max': max(ys) + margin,
            'z_min': min(zs) - margin, 'z_max': max(zs) + margin}


def scene_geometry(physics: PhysicsParams) -> dict:
    """Return what the page needs to draw the scene (m, rad, s; colours as CSS)."""
    return {
        'rod_length': physics.rod_length, 'pendulum_length': physics.pendulum_length,
        'ball_radius': physics.ball_radius, 'beam_height': BEAM_HEIGHT,
        'rod_radius': ROD_RADIUS, 'slider_width': SLIDER_SIZE[1],
        'slider_height': SLIDER_SIZE[2], 'pendulum_limit': physics.pendulum_limit,
        'control_period': physics.control_period,
        'steps_per_episode': physics.steps_per_episode,
        'bounds': scene_bounds(physics),
        'colors': {name: 'rgb({}, {}, {})'.format(*rgb) for name, rgb in COLORS.items()},
    }


# ---------------------------------------------------------------------------- documents

def state_document(state: StateView, sent_ms: float) -> dict:
    """Return the page's state event (finite numbers only), stamped with the wall send time."""
    if not state.finite():
        return {'valid': False, 'episode': state.episode, 'step': state.step,
                'sent_ms': sent_ms}
    return {'valid': True, 'episode': state.episode, 'step': state.step,
            'slider': state.slider_position, 'angle': state.pendulum_angle,
            'ball': state.ball_position, 'slider_velocity': state.slider_velocity,
            'angular_velocity': state.pendulum_angular_velocity,
            'ball_velocity': state.ball_velocity, 'final': state.final, 'sent_ms': sent_ms}


def overlay_document(words: Overlay) -> dict:
    """Return the page's words event."""
    return {'banner': words.banner, 'tone': words.tone, 'lines': list(words.lines),
            'result': list(words.result), 'countdown': words.countdown,
            'episode_label': words.episode_label, 'notice': words.notice}


def console_document(snapshot: Snapshot) -> dict:
    """Return what the experimenter's console shows (JSON-safe)."""
    session, human, now = snapshot.session, snapshot.human, snapshot.now
    source = {'source': 'unknown', 'detail': 'no human command received yet', 'age_s': None,
              'engaged': False, 'healthy': False}
    if human is not None:
        age = max(0.0, now - human.received)
        source = {'source': human.source, 'detail': human.detail, 'age_s': round(age, 2),
                  'engaged': human.engaged,
                  'healthy': (age < STALE_COMMAND_S and human.source != 'none'
                              and not snapshot.input_lost)}
    if snapshot.input_lost:
        source['detail'] = snapshot.input_lost
        if not source['detail'].startswith('joystick disconnected'):
            source['detail'] = f'joystick disconnected: {source["detail"]}'
    errors = snapshot.errors
    means = errors.means()
    totals = {'elapsed_s': (round(now - snapshot.session_started, 1)
                            if snapshot.session_started is not None else 0.0)}
    if session is not None:
        totals.update(training_episodes=session.total_episodes,
                      with_person=episodes_with_person(snapshot),
                      test_episodes=snapshot.evaluation_done,
                      training_step=f'{session.training_step + 1} of '
                      f'{max(session.training_step_count, 1)}')
    return {
        'session': None if session is None else {
            'session_id': session.session_id, 'case_id': session.case_id,
            'strategy': session.strategy, 'phase': session.phase,
            'human_involved': session.human_involved, 'message': session.message,
            'label': episode_label(session, snapshot.plan)},
        'input': source, 'input_lost': snapshot.input_lost,
        'episode': {'episode': errors.episode, 'steps': errors.steps,
                    'slider_error_m': round(means['slider'], 4),
                    'pendulum_error_rad': round(means['pendulum'], 4),
                    'ball_error_m': round(means['ball'], 4),
                    'human_missing': errors.human_missing,
                    'robot_missing': errors.robot_missing},
        'totals': totals,
        'alone': (snapshot.alone.words(now) if snapshot.alone is not None else ''),
        'practice': session is not None and session.strategy == 'practice',
        'milestone': milestone(snapshot),
        'invalid_state': snapshot.invalid_state,
    }


def status_document(snapshot: Snapshot, words: Overlay) -> dict:
    """Return the /status.json document: the words, the newest inputs and the console's data."""
    session, state = snapshot.session, snapshot.state
    document = overlay_document(words)
    document.update({
        'session': None if session is None else {
            'session_id': session.session_id, 'case_id': session.case_id,
            'strategy': session.strategy, 'phase': session.phase,
            'training_step': session.training_step, 'human_involved': session.human_involved,
            'human_dof': session.human_dof, 'human_subtasks': list(session.human_subtasks),
            'episode': session.episode, 'total_episodes': session.total_episodes,
            'human_involved_episodes': session.human_involved_episodes,
            'message': session.message},
        'state': None if state is None else {
            'episode': state.episode, 'step': state.step,
            'slider_position': state.slider_position, 'pendulum_angle': state.pendulum_angle,
            'ball_position': state.ball_position, 'final': state.final},
        'invalid_state': snapshot.invalid_state,
        'geometry_from_sim': snapshot.geometry_from_sim,
        'plan': None if snapshot.plan is None else {
            'max_training_episodes': snapshot.plan.max_training_episodes,
            'evaluation_episodes': snapshot.plan.evaluation_episodes,
            'episode_break': snapshot.plan.episode_break},
        'console': console_document(snapshot),
    })
    return document
