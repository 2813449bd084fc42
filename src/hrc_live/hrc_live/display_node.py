"""The display node (``display``): what the person sees, served as a page on localhost.

Subscribes ``/hrc/state``, ``/hrc/session`` and ``/hrc/episode``; serves on
``http://127.0.0.1:<port>/`` (localhost only):

* ``/``: a page showing the frame, refreshed ``frame_rate`` times a second;
* ``/frame.png``: the frame: the slider, rod, pendulum and ball drawn from the newest state,
  with the overlay (what the person is asked to do, "the robot is learning alone, please wait",
  the countdown to the next episode, episode x of y, the result of the last episode);
* ``/status.json``: the overlay's words and the newest inputs, for tests and other tools.

The geometry and timing come from the sim's own parameters and the episode counts and break
from the agent's, asked through their parameter services (``sim_node``, ``agent_node``), so
nothing is configured twice; until they answer the display uses the physics defaults and
leaves out "of y" and the countdown. Frames are drawn on request, at most once per change of
the inputs (or per second, for the countdown): nobody watching costs nothing.
"""

from dataclasses import dataclass, fields
import http.server
import json
import math
import threading
import time

from hrc_common import qos, topics
from hrc_common.nodes import run_node
from hrc_common.params import declare_parameters, param, ParameterError, with_overrides
from hrc_msgs.msg import EpisodeSummary, SessionStatus, TaskState
from hrc_sim_node.physics import PhysicsParams
from rcl_interfaces.srv import GetParameters
from rclpy.node import Node
from rclpy.parameter import parameter_value_to_python

from hrc_live.display_core import (AgentPlan, DisplayModel, DOF_NAMES, PHASES, render_png,
                                   ResultView, SessionView, StateView, status_document)

SUMMARY = ('The display of a live hrc session: the slider, pendulum and ball with what the '
           'person is asked to do, served on http://127.0.0.1:<port>/ (frame.png, status.json).')

# The sim's parameters the drawing needs, and the agent's the overlay needs.
SIM_PARAMETERS = ('rod_length', 'pendulum_length', 'ball_radius', 'pendulum_limit',
                  'control_period', 'episode_duration')
AGENT_PARAMETERS = ('max_training_episodes', 'evaluation_episodes', 'episode_break', 'mode')

PAGE = """<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>hrc live</title>
<style>body{{margin:0;background:#20242c}}img{{display:block;margin:auto;max-width:100vw;
max-height:100vh}}</style></head>
<body><img id="frame" src="/frame.png" alt="hrc session" width="{width}" height="{height}">
<noscript><meta http-equiv="refresh" content="1"></noscript>
<script>
const frame = document.getElementById('frame');
const period = {period_ms};
function next() {{
  const started = Date.now();
  const image = new Image();
  image.onload = () => {{ frame.src = image.src;
    setTimeout(next, Math.max(0, period - (Date.now() - started))); }};
  image.onerror = () => setTimeout(next, 1000);
  image.src = '/frame.png?t=' + started;
}}
setTimeout(next, period);
</script></body></html>
"""


@dataclass
class DisplayParams:
    """Parameters of the display node (mirrored in params/display.yaml)."""

    port: int = param(8765, 'TCP port of the page on 127.0.0.1 (localhost only); 0 = any free '
                      'port (logged)', low=0, high=65535)
    frame_rate: float = param(5.0, 'how often the page asks for a new frame (Hz); the sim '
                              'changes every control period (5 Hz)', low=0.2, high=30.0)
    width: int = param(800, 'frame width (px)', low=320, high=3840)
    height: int = param(480, 'frame height (px)', low=200, high=2160)
    result_seconds: float = param(5.0, 'the result of an episode stays up during the break '
                                  'and this long into the next episode (s)', low=0.0,
                                  high=600.0)
    sim_node: str = param('sim', 'node whose parameters give the geometry and timing')
    agent_node: str = param('agent', 'node whose parameters give the episode counts and the '
                            'break between episodes')
    query_period: float = param(1.0, 'interval between attempts to read the sim and agent '
                                'parameters until they answer (s)', low=0.05, high=60.0)


def state_view(message: TaskState) -> StateView:
    """Convert a TaskState."""
    return StateView(int(message.episode), int(message.step), float(message.slider_position),
                     float(message.pendulum_angle), float(message.ball_position),
                     bool(message.truncated or message.terminated))


def session_view(message: SessionStatus) -> SessionView:
    """Convert a SessionStatus."""
    phase = PHASES[message.phase] if message.phase < len(PHASES) else f'phase {message.phase}'
    human_dof = DOF_NAMES[message.human_dof] if message.human_dof < len(DOF_NAMES) else ''
    return SessionView(message.session_id, int(message.case_id), message.strategy,
                       int(message.training_step), int(message.training_step_count),
                       human_dof, bool(message.human_involved),
                       tuple(message.human_subtasks), int(message.episode),
                       int(message.total_episodes), int(message.human_involved_episodes),
                       phase, message.message)


def result_view(message: EpisodeSummary) -> ResultView:
    """Convert an EpisodeSummary."""
    return ResultView(int(message.episode), bool(message.evaluation),
                      bool(message.human_involved), float(message.slider_error),
                      float(message.pendulum_error), float(message.ball_error),
                      float(message.total_error), bool(message.converged))


class FrameServer:
    """The HTTP side: renders frames of the model on request, caches them, serves them."""

    def __init__(self, model: DisplayModel, params: DisplayParams, logger):
        self.model = model
        self.params = params
        self.logger = logger
        self._lock = threading.Lock()
        self._cache_key = None
        self._cache = (b'', None, None)   # PNG, Overlay, Snapshot
        self.frames_rendered = 0
        server = self

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_GET(self):  # noqa: N802 (the name http.server calls)
                server.handle(self)

            def log_message(self, format, *args):  # noqa: A002
                pass  # one line per frame would flood the log

        self.httpd = http.server.ThreadingHTTPServer(('127.0.0.1', params.port), Handler)
        self.httpd.daemon_threads = True
        self.port = self.httpd.server_address[1]
        self.thread = threading.Thread(target=self.httpd.serve_forever, name='display-http',
                                       daemon=True)
        self.thread.start()

    def frame(self):
        """Return (PNG, Overlay, Snapshot), drawn again only when something changed."""
        now = time.monotonic()
        with self._lock:
            # The overlay changes with the inputs (version) and, for the countdown and the
            # result's timeout, with the second.
            key = (self.model.version, math.floor(now))
            if key != self._cache_key:
                snapshot = self.model.snapshot(now)
                png, words = render_png(snapshot, self.params.width, self.params.height,
                                        self.params.result_seconds)
                self._cache, self._cache_key = (png, words, snapshot), key
                self.frames_rendered += 1
            return self._cache

    def handle(self, request) -> None:
        """Answer one GET request."""
        path = request.path.split('?', 1)[0]
        try:
            if path in ('/', '/index.html'):
                body = PAGE.format(width=self.params.width, height=self.params.height,
                                   period_ms=int(1000 / self.params.frame_rate)).encode()
                content_type = 'text/html; charset=utf-8'
            elif path == '/frame.png':
                body, _, _ = self.frame()
                content_type = 'image/png'
            elif path == '/status.json':
                _, words, snapshot = self.frame()
                document = status_document(snapshot, words)
                document['frames_rendered'] = self.frames_rendered
                body = json.dumps(document, indent=1).encode()
                content_type = 'application/json'
            else:
                request.send_error(404, 'not here: try /, /frame.png or /status.json')
                return
            request.send_response(200)
            request.send_header('Content-Type', content_type)
            request.send_header('Content-Length', str(len(body)))
            request.send_header('Cache-Control', 'no-store')
            request.end_headers()
            request.wfile.write(body)
        except (BrokenPipeError, ConnectionResetError):
            pass  # the browser went away mid-answer
        except Exception as error:  # a drawing bug must not kill the server thread
            self.logger.error(f'GET {path} failed: {type(error).__name__}: {error}',
                              throttle_duration_sec=5.0)
            try:
                request.send_error(500, f'{type(error).__name__}: {error}')
            except OSError:
                pass

    def close(self) -> None:
        """Stop serving and release the port."""
        self.httpd.shutdown()
        self.httpd.server_close()


class ParameterQuery:
    """Read some parameters of another node once, through its get_parameters service."""

    def __init__(self, node: Node, target: str, names: tuple, on_values):
        self.node = node
        self.target = target
        self.names = list(names)
        self.on_values = on_values
        self.client = node.create_client(GetParameters, f'/{target}/get_parameters')
        self.future = None
        self.done = False

    def poll(self) -> None:
        """Ask (again) if not answered yet and the service is there."""
        if self.done or self.future is not None or not self.client.service_is_ready():
            return
        self.future = self.client.call_async(GetParameters.Request(names=self.names))
        self.future.add_done_callback(self._on_answer)

    def restart(self) -> None:
        """Ask again (the node was restarted, e.g. a new session)."""
        self.done = False

    def _on_answer(self, future) -> None:
        self.future = None
        try:
            values = [parameter_value_to_python(value) for value in future.result().values]
        except Exception as error:  # the service call failed: try again later
            self.node.get_logger().warning(f'reading parameters of /{self.target} failed: '
                                           f'{error}', throttle_duration_sec=10.0)
            return
        if len(values) != len(self.names) or any(value is None for value in values):
            self.node.get_logger().warning(
                f'/{self.target} lacks some of the parameters {self.names}: got {values}',
                throttle_duration_sec=10.0)
            return
        self.done = True
        self.on_values(dict(zip(self.names, values)))


class DisplayNode(Node):
    """Feeds a DisplayModel from the topics and serves its frames (see the module docstring)."""

    def __init__(self):
        super().__init__('display')
        self.params = params = declare_parameters(self, DisplayParams)
        self.model = DisplayModel()
        self.create_subscription(TaskState, topics.STATE, self.on_state, qos.STATE_QOS)
        self.create_subscription(SessionStatus, topics.SESSION, self.on_session,
                                 qos.SESSION_QOS)
        self.create_subscription(EpisodeSummary, topics.EPISODE, self.on_episode,
                                 qos.EPISODE_QOS)
        self.sim_query = ParameterQuery(self, params.sim_node, SIM_PARAMETERS, self.on_sim)
        self.agent_query = ParameterQuery(self, params.agent_node, AGENT_PARAMETERS,
                                          self.on_agent)
        self.create_timer(params.query_period, self.poll_queries)
        self.session_id = None
        try:
            self.server = FrameServer(self.model, params, self.get_logger())
        except OSError as error:
            raise ParameterError(f'DisplayParams rejected: port: cannot serve on '
                                 f'127.0.0.1:{params.port}: {error.strerror}') from None
        self.get_logger().info(
            f'serving the display on http://127.0.0.1:{self.server.port}/ (frame.png, '
            f'status.json), {params.width}x{params.height} px at {params.frame_rate} Hz; '
            f'geometry from /{params.sim_node}, episodes from /{params.agent_node}')

    def poll_queries(self):
        """Ask the sim and the agent for their parameters until they answer."""
        self.sim_query.poll()
        self.agent_query.poll()

    def on_sim(self, values: dict):
        """Take the sim's geometry and timing."""
        try:
            physics = with_overrides(PhysicsParams(), **{
                name: values[name] for name in SIM_PARAMETERS
                if name in {field.name for field in fields(PhysicsParams)}})
        except (ParameterError, TypeError) as error:
            self.get_logger().warning(f'/{self.params.sim_node} parameters unusable: {error}')
            return
        self.model.set_physics(physics)
        self.get_logger().info(f'geometry from /{self.params.sim_node}: ' + ', '.join(
            f'{name} {values[name]}' for name in SIM_PARAMETERS))

    def on_agent(self, values: dict):
        """Take the agent's episode counts and break (no break in lockstep)."""
        episode_break = values['episode_break'] if values['mode'] == 'realtime' else 0.0
        self.model.set_plan(AgentPlan(int(values['max_training_episodes']),
                                      int(values['evaluation_episodes']),
                                      float(episode_break)))
        self.get_logger().info(f'episodes from /{self.params.agent_node}: at most '
                               f'{values["max_training_episodes"]} training, '
                               f'{values["evaluation_episodes"]} evaluation, break '
                               f'{episode_break} s')

    def on_state(self, message: TaskState):
        """Take a new state."""
        self.model.on_state(state_view(message), time.monotonic())

    def on_session(self, message: SessionStatus):
        """Take a new session status; a new session id means a new agent: ask it again."""
        if message.session_id != self.session_id:
            if self.session_id is not None:
                self.agent_query.restart()
                self.sim_query.restart()
            self.session_id = message.session_id
            self.get_logger().info(f'showing session {message.session_id!r} (case '
                                   f'{message.case_id}, {message.strategy})')
        self.model.on_session(session_view(message), time.monotonic())

    def on_episode(self, message: EpisodeSummary):
        """Take the summary of a finished episode."""
        self.model.on_result(result_view(message), time.monotonic())

    def close(self):
        """Stop the HTTP server."""
        server = getattr(self, 'server', None)
        if server is not None:
            server.close()


def main(args=None):
    """Run the display node (``ros2 run hrc_live display_node``)."""
    return run_node(DisplayNode, 'display_node', SUMMARY, DisplayParams, args=args)


if __name__ == '__main__':
    raise SystemExit(main())
