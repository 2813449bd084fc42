"""What the Foxglove live view shows, as plain values (pure: no rclpy, no Foxglove SDK).

The foxglove node (:mod:`hrc_live.foxglove_node`) turns the session's messages into these
records and logs them on the channels below; ``params/foxglove/hrc_layout.json`` lays them out.
Channels (topic names of the Foxglove server, not ROS topics):

* ``/hrc/scene`` (``foxglove.SceneUpdate``): the rod, the slider, the beam and the ball, posed
  as the sim's model (:func:`hrc_sim_node.body_geometry.body_poses`) in frame ``world``.
* ``/hrc/errors`` (JSON): each subtask's error at the state, |S_x| m, |P_z| rad, |B_y| m.
* ``/hrc/agent`` (JSON): the robot's reward and both actors' actions (normalized, [-1, 1]).
* ``/hrc/session`` (JSON): the session's phase, episode and line of what happens now.

Every record carries ``episode`` and ``step`` so a plot can be read against the bags.
"""

from dataclasses import dataclass

from hrc_common.contract import BODY_COLOURS
from hrc_common.params import param
from hrc_sim_node.body_geometry import body_poses, body_shapes

SCENE_FRAME = 'world'
PHASE_NAMES = ('training', 'updating', 'evaluation', 'paused', 'done', 'aborted')

ERRORS_SCHEMA = {'type': 'object', 'properties': {
    'episode': {'type': 'integer'}, 'step': {'type': 'integer'},
    'slider_m': {'type': 'number'}, 'pendulum_rad': {'type': 'number'},
    'ball_m': {'type': 'number'}}}
AGENT_SCHEMA = {'type': 'object', 'properties': {
    'episode': {'type': 'integer'}, 'step': {'type': 'integer'},
    'reward': {'type': 'number'}, 'robot_action': {'type': 'number'},
    'human_action': {'type': 'number'}, 'deterministic': {'type': 'boolean'}}}
SESSION_SCHEMA = {'type': 'object', 'properties': {
    'session_id': {'type': 'string'}, 'case': {'type': 'integer'},
    'phase': {'type': 'string'}, 'episode': {'type': 'integer'},
    'human_involved': {'type': 'boolean'}, 'message': {'type': 'string'}}}


@dataclass
class FoxgloveParams:
    """Parameters of the foxglove node (node ``foxglove``, params/foxglove.yaml)."""

    port: int = param(8766, 'TCP port of the Foxglove WebSocket server (Foxglove: Open '
                      'connection, ws://<host>:<port>); 0 = any free port (logged)', low=0,
                      high=65535)
    host: str = param('127.0.0.1', 'address the server listens on (127.0.0.1: this computer '
                      'only; 0.0.0.0: every interface, for a viewer on another computer)')
    max_rate: float = param(
        30.0, 'each channel is logged at most this often (Hz, wall time): a realtime session '
        '(5 states/s) shows every state, a lockstep one a sample', low=0.5, high=1000.0)
    sim_node: str = param('sim', 'node whose parameters give the geometry of the scene')


class RateLimit:
    """Admit at most ``rate`` events per second of wall time (the caller's clock, s)."""

    def __init__(self, rate: float):
        self.period = 1.0 / rate
        self._next = None

    def admit(self, now: float) -> bool:
        """Return True if an event at ``now`` may pass."""
        if self._next is not None and now < self._next:
            return False
        self._next = now + self.period
        return True


def scene_bodies(state, physics) -> list:
    """Return the bodies of the scene at ``state`` as plain records.

    ``state``: anything with the TaskState's slider_position, pendulum_angle and ball_position;
    ``physics``: PhysicsParams (the geometry). Each record: id, shape ('cylinder' | 'cube' |
    'sphere'), position (m), orientation (x, y, z, w), size (m), colour (r, g, b, a).
    """
    shapes = body_shapes(physics)
    return [{'id': name, 'shape': shapes[name][0], 'position': position,
             'orientation': orientation, 'size': shapes[name][1],
             'colour': (*BODY_COLOURS[name], 1.0)}
            for name, (position, orientation) in body_poses(state, physics).items()]


def errors_record(state) -> dict:
    """Return the subtask errors at a TaskState (the EpisodeSummary's, before averaging)."""
    return {'episode': int(state.episode), 'step': int(state.step),
            'slider_m': abs(float(state.slider_position)),
            'pendulum_rad': abs(float(state.pendulum_angle)),
            'ball_m': abs(float(state.ball_position))}


def agent_record(step) -> dict:
    """Return the robot's reward and both actions of an AgentStep."""
    return {'episode': int(step.episode), 'step': int(step.step),
            'reward': float(step.reward), 'robot_action': float(step.action),
            'human_action': float(step.observation_human_action),
            'deterministic': bool(step.deterministic)}


def session_record(status) -> dict:
    """Return what the session says now (a SessionStatus)."""
    phase = int(status.phase)
    return {'session_id': str(status.session_id), 'case': int(status.case_id),
            'phase': PHASE_NAMES[phase] if phase < len(PHASE_NAMES) else str(phase),
            'episode': int(status.episode), 'human_involved': bool(status.human_involved),
            'message': str(status.message)}
