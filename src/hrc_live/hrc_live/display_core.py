"""What the person at the joystick sees: the bodies and the instructions, drawn into one frame.

Pure (no rclpy): the display node feeds :class:`DisplayModel` with what arrives on
``/hrc/state``, ``/hrc/session`` and ``/hrc/episode`` (converted to the plain views below) and
serves :func:`render_png` of a :meth:`DisplayModel.snapshot` over HTTP.

The frame (``width`` x ``height`` px) has two parts:

* the scene, left: the system seen from the viewer (world +x), east to the right, up is up,
  drawn from the state with the sim's own geometry (:func:`hrc_sim_node.physics.body_poses`)
  and colours (rod grey, slider orange, pendulum blue, ball grey), with the targets marked (the
  middle of the rod, the level line, the middle of the beam); a banner on top says what the
  person is asked to do now; between episodes a box shows the result and the countdown;
* the panel, right: episode x of y, training step, the person's degree of freedom and
  subtasks, time left in the episode, the last result.

The wording for the person is in :func:`overlay`, one place, tested on its own.
"""

from dataclasses import dataclass, replace
import functools
import io
import math
import threading
import typing

from hrc_sim_node.physics import (BEAM_HEIGHT, body_poses, PhysicsParams, ROD_RADIUS,
                                  SLIDER_SIZE)

# Phase names in SessionStatus.PHASE_* order.
PHASES = ('training', 'updating', 'evaluation', 'paused', 'done', 'aborted')
DOF_NAMES = ('translation', 'rotation')  # SessionStatus.DOF_* order

# The sim's colours (hrc_sim_node.physics.model_urdf), as 8-bit RGB.
ROD_COLOR = (153, 153, 153)
SLIDER_COLOR = (255, 140, 26)
PENDULUM_COLOR = (38, 89, 217)
BALL_COLOR = (115, 115, 115)
BACKGROUND_COLOR = (242, 243, 245)
TARGET_COLOR = (200, 204, 210)
PANEL_COLOR = (32, 36, 44)
PANEL_TEXT_COLOR = (235, 238, 242)
PANEL_DIM_COLOR = (160, 168, 180)
# Banner colours by what the person should do: act, wait, stop, or nothing yet.
BANNER_COLORS = {'act': (24, 110, 60), 'wait': (178, 110, 0), 'stop': (170, 32, 32),
                 'info': (60, 66, 78)}

# What each subtask asks of the person, and what each degree of freedom gives them.
SUBTASK_WORDS = {'slider': 'keep the slider in the middle of the rod',
                 'pendulum': 'keep the pendulum level',
                 'ball': 'keep the ball in the middle of the pendulum'}
CONTROL_WORDS = {'translation': 'You move the slider up and down (stick up = up).',
                 'rotation': 'You tilt the pendulum (stick up = right end up).'}

# Fraction of the frame width given to the text panel.
PANEL_FRACTION = 0.4


@dataclass(frozen=True)
class StateView:
    """What the display needs of a TaskState."""

    episode: int
    step: int
    slider_position: float      # S_x (m)
    pendulum_angle: float       # P_z (rad)
    ball_position: float        # B_y (m)
    final: bool                 # truncated or terminated: the episode is over


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
class AgentPlan:
    """The agent's parameters the overlay uses (asked from the agent node)."""

    max_training_episodes: int
    evaluation_episodes: int
    episode_break: float        # s between episodes (realtime), 0 in lockstep


@dataclass(frozen=True)
class Snapshot:
    """Everything a frame shows, at one instant (monotonic s ``now``)."""

    now: float
    physics: PhysicsParams
    state: typing.Optional[StateView] = None
    session: typing.Optional[SessionView] = None
    result: typing.Optional[ResultView] = None
    previous_result: typing.Optional[ResultView] = None
    plan: typing.Optional[AgentPlan] = None
    break_started: typing.Optional[float] = None    # monotonic s the current break began
    result_time: typing.Optional[float] = None      # monotonic s the last result arrived
    episode_started: typing.Optional[float] = None  # monotonic s step 0 of the episode arrived
    geometry_from_sim: bool = False


@dataclass(frozen=True)
class Overlay:
    """The words of one frame."""

    banner: str
    tone: str                   # a key of BANNER_COLORS
    lines: tuple                # the panel's lines
    result: tuple = ()          # the result box's lines (empty: no box)
    countdown: typing.Optional[int] = None  # whole seconds to the next episode, if known
    episode_label: str = ''


def episode_label(session: SessionView, plan: typing.Optional[AgentPlan]) -> str:
    """Return "Episode x of y" for the current (or next) episode."""
    if session.phase == 'done':
        return f'{session.total_episodes} training episodes done'
    evaluating = session.phase == 'evaluation' or (
        session.phase in ('paused', 'done', 'aborted') and plan is not None
        and session.episode > session.total_episodes)
    if evaluating:
        index = session.episode - session.total_episodes + 1
        total = f' of {plan.evaluation_episodes}' if plan is not None else ''
        return f'Test episode {max(index, 1)}{total}'
    total = f' of at most {plan.max_training_episodes}' if plan is not None else ''
    return f'Episode {session.total_episodes + 1}{total}'


def result_lines(result: ResultView, previous: typing.Optional[ResultView]) -> tuple:
    """Return the short result of an episode, in the person's terms."""
    kind = 'Test episode' if result.evaluation else 'Episode'
    lines = [f'{kind} {result.episode + 1} done',
             f'ball off centre: {100 * result.ball_error:.1f} cm on average',
             f'pendulum tilt: {math.degrees(result.pendulum_error):.1f} deg, '
             f'slider: {100 * result.slider_error:.1f} cm']
    if previous is not None and previous.total_error > 0:
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


def overlay(snapshot: Snapshot, result_seconds: float = 5.0) -> Overlay:
    """Return the banner, panel lines, result box and countdown of ``snapshot``."""
    session, state, plan, now = snapshot.session, snapshot.state, snapshot.plan, snapshot.now
    if session is None:
        return Overlay('Please wait: the session is starting', 'info',
                       ('Waiting for the robot to announce the session.',))
    label = episode_label(session, plan)
    lines = [label]
    if session.training_step_count > 1:
        lines.append(f'Training step {session.training_step + 1} of '
                     f'{session.training_step_count}')
    in_episode = state is not None and not state.final
    if session.human_involved:
        lines.append(CONTROL_WORDS.get(session.human_dof, ''))
        tasks = [SUBTASK_WORDS.get(subtask, subtask) for subtask in session.human_subtasks]
        lines += [f'Your task: {task}.' for task in tasks]
    else:
        lines.append('The robot works alone in this step.')
    if in_episode:
        steps_left = max(0, snapshot.physics.steps_per_episode - state.step)
        lines.append(f'Time left: {steps_left * snapshot.physics.control_period:.0f} s')
    lines.append(f'Episodes with you so far: {session.human_involved_episodes}')

    result = ()
    # The result stays up during the break and the first seconds of the next episode.
    showing_result = snapshot.result is not None and (
        not in_episode or (snapshot.episode_started is not None
                           and now - snapshot.episode_started < result_seconds))
    if showing_result:
        result = result_lines(snapshot.result, snapshot.previous_result)
    if snapshot.result is not None:
        lines.append(f'Last episode: ball {100 * snapshot.result.ball_error:.1f} cm off centre')

    countdown = None
    if (not in_episode and plan is not None and plan.episode_break > 0
            and snapshot.break_started is not None
            and session.phase in ('training', 'updating', 'evaluation')):
        countdown = max(0, math.ceil(snapshot.break_started + plan.episode_break - now))

    phase = session.phase
    if phase == 'aborted':
        banner, tone = 'Stopped by the operator. Please let go of the joystick.', 'stop'
    elif phase == 'done':
        banner, tone = 'The session is finished. Thank you!', 'info'
    elif phase == 'paused':
        banner, tone = 'Paused: please wait for the operator', 'wait'
    elif not in_episode:
        if phase == 'updating':
            banner = 'The robot is learning from the last episode: please wait'
        elif countdown:
            banner = f'Next episode in {countdown} s'
        else:
            banner = 'The next episode is starting'
        tone = 'wait'
        if not session.human_involved:
            lines.insert(1, 'The robot is learning alone, please wait.')
    elif not session.human_involved:
        banner, tone = 'The robot is learning alone, please wait', 'wait'
    else:
        tasks = [SUBTASK_WORDS.get(subtask, subtask) for subtask in session.human_subtasks]
        banner = ('Your turn: ' + ' and '.join(tasks)) if tasks else 'Your turn'
        tone = 'act'
    return Overlay(banner, tone, tuple(line for line in lines if line), result, countdown,
                   label)


class DisplayModel:
    """The newest state, session, results and parameters, shared between threads.

    The ROS executor thread calls the ``on_*`` methods; the HTTP threads call :meth:`snapshot`.
    ``now`` is monotonic seconds, passed in so that tests control time.
    """

    def __init__(self, physics: PhysicsParams = None):
        self._lock = threading.Lock()
        self._snapshot = Snapshot(now=0.0, physics=physics or PhysicsParams())
        self.version = 0            # increases with every change (frame cache key)

    def _update(self, **changes) -> None:
        self._snapshot = replace(self._snapshot, **changes)
        self.version += 1

    def on_state(self, state: StateView, now: float) -> None:
        """Take a new state; step 0 starts an episode, a final state starts the break."""
        with self._lock:
            previous = self._snapshot.state
            changes = {'state': state}
            if state.step == 0 or previous is None or previous.episode != state.episode:
                changes['episode_started'] = now
            if state.final and not (previous is not None and previous.final
                                    and previous.episode == state.episode):
                changes['break_started'] = now
            self._update(**changes)

    def on_session(self, session: SessionView, now: float) -> None:
        """Take a new session status; a resume restarts the break (the agent waits again)."""
        with self._lock:
            previous = self._snapshot.session
            changes = {'session': session}
            if previous is not None and previous.session_id != session.session_id:
                changes['plan'] = None  # another agent: ask again
            if previous is not None and previous.phase == 'paused' and session.phase != 'paused':
                changes['break_started'] = now
            self._update(**changes)

    def on_result(self, result: ResultView, now: float) -> None:
        """Take the summary of a finished episode (repeats of the same one are ignored)."""
        with self._lock:
            current = self._snapshot.result
            if current is not None and current.episode == result.episode:
                return
            self._update(result=result, previous_result=current, result_time=now)

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


# ---------------------------------------------------------------------------- drawing

@dataclass(frozen=True)
class Layout:
    """Where things go in a frame of ``width`` x ``height`` px (world in m -> pixels)."""

    width: int
    height: int
    scene_width: int
    banner_height: int
    scale: float                # px per m
    origin_x: float             # px of world y = 0 (the rod)
    origin_y: float             # px of world z = 0 (the middle of the rod)

    def to_pixels(self, y: float, z: float) -> tuple:
        """Return the pixel (column, row) of the world point (y east, z up)."""
        return (self.origin_x + y * self.scale, self.origin_y - z * self.scale)


def layout(physics: PhysicsParams, width: int, height: int) -> Layout:
    """Fit the rod and the whole beam, level, and tilted up to ~40 deg, into the scene."""
    scene_width = int(width * (1 - PANEL_FRACTION))
    banner_height = max(24, height // 10)
    west, east = 0.12, physics.pendulum_length + 0.06        # m either side of the rod
    half_height = physics.rod_length / 2 + 0.6 * physics.pendulum_length
    scene_height = height - banner_height
    scale = min(scene_width / (west + east), scene_height / (2 * half_height))
    origin_x = (scene_width - (west + east) * scale) / 2 + west * scale
    origin_y = banner_height + scene_height / 2
    return Layout(width, height, scene_width, banner_height, scale, origin_x, origin_y)


@functools.lru_cache(maxsize=32)
def _font(size: int):
    """Return the default font at ``size`` px (loading a TrueType font costs milliseconds)."""
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow without FreeType: the fixed bitmap font
        return ImageFont.load_default()


def _wrap(draw, text: str, font, width: float) -> list:
    """Split ``text`` into lines no wider than ``width`` px."""
    words, lines, line = text.split(), [], ''
    for word in words:
        candidate = f'{line} {word}'.strip()
        if line and draw.textlength(candidate, font=font) > width:
            lines.append(line)
            line = word
        else:
            line = candidate
    if line:
        lines.append(line)
    return lines


def _beam_polygon(start, end, thickness: float) -> list:
    """Return the corners of a bar of ``thickness`` px from ``start`` to ``end`` (pixels)."""
    dx, dy = end[0] - start[0], end[1] - start[1]
    length = math.hypot(dx, dy) or 1.0
    nx, ny = -dy / length * thickness / 2, dx / length * thickness / 2
    return [(start[0] + nx, start[1] + ny), (end[0] + nx, end[1] + ny),
            (end[0] - nx, end[1] - ny), (start[0] - nx, start[1] - ny)]


def draw_scene(draw, snapshot: Snapshot, frame: Layout) -> None:
    """Draw the targets, rod, slider, pendulum and ball of the snapshot's state."""
    physics = snapshot.physics
    state = snapshot.state or StateView(0, 0, 0.0, 0.0, 0.0, False)
    to_px = frame.to_pixels
    # Targets: the level line through the middle of the rod.
    level_y = frame.origin_y
    for x in range(0, frame.scene_width, 16):
        draw.line([(x, level_y), (x + 8, level_y)], fill=TARGET_COLOR, width=2)
    # Rod (2 cm longer than the slider's travel at each end, as in the sim's model).
    half_rod = physics.rod_length / 2 + 0.02
    rod_half_px = max(2.0, ROD_RADIUS * frame.scale)
    top, bottom = to_px(0.0, half_rod), to_px(0.0, -half_rod)
    draw.rectangle([top[0] - rod_half_px, top[1], top[0] + rod_half_px, bottom[1]],
                   fill=ROD_COLOR)
    middle = to_px(0.0, 0.0)
    draw.line([(middle[0] - 3 * rod_half_px, middle[1]), (middle[0] + 3 * rod_half_px,
                                                          middle[1])], fill=(40, 40, 40), width=2)
    poses = body_poses(_physics_state(state), physics)
    # Slider: a box centred on the hinge (SLIDER_SIZE: x depth, y width, z height).
    slider_y, slider_z = poses['slider'][0][1], poses['slider'][0][2]
    half_w = max(6.0, SLIDER_SIZE[1] / 2 * frame.scale)
    half_h = max(4.0, SLIDER_SIZE[2] / 2 * frame.scale)
    centre = to_px(slider_y, slider_z)
    draw.rectangle([centre[0] - half_w, centre[1] - half_h, centre[0] + half_w,
                    centre[1] + half_h], fill=SLIDER_COLOR)
    # Pendulum: from the hinge to its east end.
    angle = state.pendulum_angle
    hinge = to_px(0.0, state.slider_position)
    tip = to_px(physics.pendulum_length * math.cos(angle),
                state.slider_position + physics.pendulum_length * math.sin(angle))
    thickness = max(6.0, BEAM_HEIGHT * frame.scale)
    draw.polygon(_beam_polygon(hinge, tip, thickness), fill=PENDULUM_COLOR)
    # The beam's middle (the ball's target): a white notch across the beam.
    half = physics.pendulum_length / 2
    mid = to_px(half * math.cos(angle), state.slider_position + half * math.sin(angle))
    normal = (math.sin(angle), math.cos(angle))
    draw.line([(mid[0] - normal[0] * thickness, mid[1] - normal[1] * thickness),
               (mid[0] + normal[0] * thickness, mid[1] + normal[1] * thickness)],
              fill=(255, 255, 255), width=2)
    # Ball on top of the beam.
    ball = to_px(poses['ball'][0][1], poses['ball'][0][2])
    radius = max(5.0, physics.ball_radius * frame.scale)
    draw.ellipse([ball[0] - radius, ball[1] - radius, ball[0] + radius, ball[1] + radius],
                 fill=BALL_COLOR)


def _physics_state(state: StateView):
    """Return the PhysicsState-like object body_poses reads."""
    from hrc_sim_node.physics import PhysicsState

    return PhysicsState(step=state.step, time=0.0, slider_position=state.slider_position,
                        slider_velocity=0.0, pendulum_angle=state.pendulum_angle,
                        pendulum_angular_velocity=0.0, ball_position=state.ball_position,
                        ball_velocity=0.0, applied_force=0.0, applied_torque=0.0,
                        terminated=False, truncated=state.final)


def draw_overlay(draw, words: Overlay, frame: Layout) -> None:
    """Draw the banner, the panel and (between episodes) the result box."""
    height = frame.height
    banner_font = _font(max(12, frame.banner_height // 2))
    draw.rectangle([0, 0, frame.scene_width, frame.banner_height],
                   fill=BANNER_COLORS.get(words.tone, BANNER_COLORS['info']))
    banner_lines = _wrap(draw, words.banner, banner_font, frame.scene_width - 20)[:2]
    if len(banner_lines) > 1:
        banner_font = _font(max(10, frame.banner_height // 3))
        banner_lines = _wrap(draw, words.banner, banner_font, frame.scene_width - 20)[:2]
    line_height = frame.banner_height / (len(banner_lines) + 0.4)
    for index, line in enumerate(banner_lines):
        draw.text((10, line_height * (index + 0.2)), line, fill=(255, 255, 255),
                  font=banner_font)
    # Panel.
    draw.rectangle([frame.scene_width, 0, frame.width, height], fill=PANEL_COLOR)
    size = max(10, height // 26)
    font, small = _font(size), _font(max(9, int(size * 0.8)))
    x, y = frame.scene_width + 14, 12
    panel_width = frame.width - frame.scene_width - 24
    for index, text in enumerate(words.lines):
        use = font if index == 0 else small
        color = PANEL_TEXT_COLOR if index == 0 else PANEL_DIM_COLOR
        for line in _wrap(draw, text, use, panel_width):
            if y <= height - size:
                draw.text((x, y), line, fill=color, font=use)
            y += int(size * (1.35 if index == 0 else 1.15))
        y += int(size * 0.35)
    # The result box: at the bottom of the panel, between episodes and a little after.
    if words.result:
        box_font = _font(size)
        wrapped = [line for text in words.result
                   for line in _wrap(draw, text, box_font, panel_width - 16)]
        box_height = int(size * 1.3 * len(wrapped) + size)
        left, right, bottom = frame.scene_width + 8, frame.width - 8, height - 8
        top = max(y, bottom - box_height)
        draw.rectangle([left, top, right, bottom], fill=(255, 255, 255),
                       outline=BANNER_COLORS['info'], width=2)
        for index, line in enumerate(wrapped):
            row = top + size * 0.5 + index * size * 1.3
            if row > bottom - size:
                break
            draw.text((left + 8, row), line, fill=(20, 24, 30), font=box_font)


def render(snapshot: Snapshot, width: int, height: int, result_seconds: float = 5.0):
    """Return the frame of ``snapshot`` as a PIL image (RGB) and its Overlay."""
    from PIL import Image, ImageDraw

    frame = layout(snapshot.physics, width, height)
    image = Image.new('RGB', (width, height), BACKGROUND_COLOR)
    draw = ImageDraw.Draw(image)
    draw_scene(draw, snapshot, frame)
    words = overlay(snapshot, result_seconds)
    draw_overlay(draw, words, frame)
    return image, words


def render_png(snapshot: Snapshot, width: int, height: int, result_seconds: float = 5.0):
    """Return (PNG bytes, Overlay) of the frame of ``snapshot``."""
    image, words = render(snapshot, width, height, result_seconds)
    buffer = io.BytesIO()
    # Fast compression: a frame is re-encoded up to frame_rate times a second.
    image.save(buffer, format='PNG', compress_level=1)
    return buffer.getvalue(), words


def status_document(snapshot: Snapshot, words: Overlay) -> dict:
    """Return the /status.json document: the overlay's words and the newest inputs."""
    session, state = snapshot.session, snapshot.state
    return {
        'banner': words.banner, 'tone': words.tone, 'lines': list(words.lines),
        'result': list(words.result), 'countdown': words.countdown,
        'episode_label': words.episode_label,
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
        'geometry_from_sim': snapshot.geometry_from_sim,
        'plan': None if snapshot.plan is None else {
            'max_training_episodes': snapshot.plan.max_training_episodes,
            'evaluation_episodes': snapshot.plan.evaluation_episodes,
            'episode_break': snapshot.plan.episode_break},
    }

