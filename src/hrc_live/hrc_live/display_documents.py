"""The JSON documents the display pushes to its pages, and the scene's geometry.

Pure: :func:`scene_geometry` gives the sim's geometry and the world box the page fits to the
window, so that the whole reachable configuration (beam at either hinge stop, ball at either
end stop, slider at either end of the rod) is always in the picture; :func:`state_document`,
:func:`overlay_document`, :func:`console_document` and :func:`status_document` are the events
and ``/status.json``. Non-finite numbers never reach JSON: a state with one is replaced by a
notice (:func:`state_document`).
"""

import math

from hrc_common.contract import BODY_COLOURS, rgb8
from hrc_sim_node.body_geometry import BEAM_HEIGHT, body_poses, ROD_RADIUS, SLIDER_SIZE
from hrc_sim_node.physics import PhysicsParams, PhysicsState

from hrc_live.display_core import Overlay, Snapshot, StateView
from hrc_live.display_words import episode_label, episodes_with_person, milestone


# The bodies' colours (hrc_common.contract, as the sim draws them) as 8-bit RGB, and the page's.
COLORS = {**{name: rgb8(colour) for name, colour in BODY_COLOURS.items()},
          'background': (242, 243, 245), 'target': (200, 204, 210)}
# A human command older than this (s) counts as stale on the console.
STALE_COMMAND_S = 1.0
# s: a node's /diagnostics status older than this is stale (they come once a second)
STALE_HEALTH_S = 3.0
HEALTH_LEVELS = ('OK', 'WARN', 'ERROR', 'STALE')     # diagnostic_msgs/DiagnosticStatus
HEALTH_TONES = ('ok', 'wait', 'bad', 'wait')


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


def input_tone(snapshot: Snapshot, healthy: bool) -> str:
    """Return the console's colour of the person's input: 'bad' only when it asks for action.

    Red means "act now": the input is lost, or stale while the person should be acting in a
    running episode. While the robot learns alone, during a pause or between sessions a
    missing command is normal and shown without colour.
    """
    session = snapshot.session
    if snapshot.input_lost:
        return 'bad'
    acting = (session is not None and session.human_involved
              and session.phase in ('training', 'evaluation') and not snapshot.interrupted
              and snapshot.state is not None and not snapshot.state.final)
    if not acting:
        return ''
    return 'ok' if healthy else 'bad'


def health_rows(snapshot: Snapshot) -> list:
    """Return each node's newest /diagnostics status as the console shows it (by name).

    Levels and thresholds are the nodes' own (``hrc_common.diagnostics``); a status that has not
    come again for ``STALE_HEALTH_S`` is shown stale: its node may be gone or stalled.
    """
    rows = []
    for name, level, message, received in snapshot.health:
        age = max(0.0, snapshot.now - received)
        level = min(max(level, 0), len(HEALTH_LEVELS) - 1)
        words, tone = f'{HEALTH_LEVELS[level]}: {message}', HEALTH_TONES[level]
        if age > STALE_HEALTH_S:
            words, tone = f'no word for {age:.0f} s (last: {words})', 'wait'
        rows.append({'name': name, 'status': words, 'tone': tone})
    return rows


def console_document(snapshot: Snapshot, study: dict = None, tlx: str = '') -> dict:
    """Return what the experimenter's console shows (JSON-safe).

    ``study``: the subject id and the condition with its place in the subject's order (given
    to the display by the session runner); ``tlx``: where the NASA-TLX of this condition is.
    """
    session, human, now = snapshot.session, snapshot.human, snapshot.now
    source = {'source': 'unknown', 'detail': 'no human command received yet', 'age_s': None,
              'engaged': False, 'healthy': False}
    if session is not None and not session.human_involved:
        # the human node sends nothing while the person sits out (older sessions' bags hold
        # zeros then): say why, whichever
        source = {'source': 'none', 'age_s': None, 'engaged': False, 'healthy': False,
                  'detail': 'not involved in this training step: the robot learns alone, '
                            'nothing of the person is applied'}
    elif human is not None:
        age = max(0.0, now - human.received)
        source = {'source': human.source, 'detail': human.detail, 'age_s': round(age, 2),
                  'engaged': human.engaged,
                  'healthy': (age < STALE_COMMAND_S and human.source != 'none'
                              and not snapshot.input_lost)}
    if snapshot.input_lost:
        source['detail'] = snapshot.input_lost
        if not source['detail'].startswith('joystick disconnected'):
            source['detail'] = f'joystick disconnected: {source["detail"]}'
    source['tone'] = input_tone(snapshot, source['healthy'])
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
        'input': source, 'input_lost': snapshot.input_lost, 'health': health_rows(snapshot),
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
        'runner_waiting': snapshot.runner_waiting,
        'replay': snapshot.replay,
        'study': dict(study or {}),
        'tlx': tlx,
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
