"""The display node (``display``): the person's page and the experimenter's console, on localhost.

Subscribes ``/hrc/state``, ``/hrc/session``, ``/hrc/episode`` and ``/hrc/human/action``; serves
on ``http://127.0.0.1:<port>/`` (localhost only; from another machine use ``ssh -L``):

* ``/``: the person's page: the scene drawn in the browser (canvas) from the states pushed on
  ``/events``, the banner (what to do now), the panel (episode x of y, the task, time left),
  the result of the last episode, the countdown, and after a condition the NASA-TLX form;
* ``/console``: the experimenter's console: input source and health (command age, missing
  commands), the running episode's errors, the totals, pause / resume / abort buttons;
* ``/events``: Server-Sent Events: ``geometry`` (once per client and when the sim's geometry
  is read), ``state`` (every state, at the control rate, stamped with the wall send time),
  ``words`` and ``console`` (when they change, checked ``words_rate`` times a second), ``tlx``;
* ``/status.json``: the words, the newest inputs and the console's data, for tests and tools;
* ``POST /control/<pause|resume|abort>``: the agent's operator services (as ``operator``);
* ``POST /tlx``: the raw NASA-TLX of the condition just finished, appended to ``tlx_file``.

Only the lab's own pages may act (``RequestGuard``): every request must name a loopback host or
the served address in ``Host`` (a DNS-rebinding site cannot even read ``/status.json``); every
``POST`` must come from the server's own origin (``Origin``) and carry the session's secret in
the ``X-HRC-Token`` header, a random token written into the pages when they are served (never
in a URL, so never in a log). Anything else is refused with 403 and logged. A malformed
request (a bad ``Content-Length``) is answered 400; a body over ``MAX_BODY`` bytes 413.

The geometry and timing come from the sim's own parameters and the episode counts and break
from the agent's, asked through their parameter services (``sim_node``, ``agent_node``), so
nothing is configured twice. A lost input of the person (``input_lost_topic``, set by the
session runner) shows "joystick disconnected" on both pages.
"""

from dataclasses import fields
import datetime
import http.server
import json
import os
import pathlib
import queue
import secrets
import sys
import threading
import time

from hrc_common import qos, topics
from hrc_common.contract import atomic_write, dof_name, PERSONAL_FILE_MODE, phase_label
from hrc_common.nodes import run_node
from hrc_common.parameter_query import ParameterQuery
from hrc_common.params import declare_parameters, ParameterError, with_overrides
from hrc_common.session_control import OPERATOR_SERVICES
from hrc_common.tlx import check_tlx, raw_tlx, TLX_STEP
from hrc_msgs.msg import EpisodeSummary, HumanAction, SessionStatus, TaskState
from hrc_sim_node.physics import PhysicsParams
from rclpy.node import Node
from std_msgs.msg import String
from std_srvs.srv import Trigger
import yaml

from hrc_live.display_core import (AgentPlan, console_document, DisplayModel, HumanView,
                                   overlay, overlay_document, ResultView, scene_geometry,
                                   SessionView, SOURCE_NAMES, state_document, StateView,
                                   status_document)
from hrc_live.display_params import DisplayParams
from hrc_live.input_check import INPUT_LOST_TOPIC

SUMMARY = ("The pages of a live hrc session on http://127.0.0.1:<port>/: the person's page "
           '(scene drawn in the browser from a pushed state stream) and /console for the '
           'experimenter (input health, errors, pause/resume/abort).')
WEB = pathlib.Path(__file__).resolve().parent / 'web'
FILES = {'/': ('person.html', 'text/html; charset=utf-8'),
         '/index.html': ('person.html', 'text/html; charset=utf-8'),
         '/console': ('console.html', 'text/html; charset=utf-8'),
         '/scene.js': ('scene.js', 'text/javascript; charset=utf-8')}

# The sim's parameters the drawing needs, and the agent's the overlay needs.
SIM_PARAMETERS = ('rod_length', 'pendulum_length', 'ball_radius', 'pendulum_limit',
                  'control_period', 'episode_duration')
AGENT_PARAMETERS = ('max_training_episodes', 'evaluation_episodes', 'episode_break', 'mode')
# Events kept per client before the oldest are dropped (a stalled browser must not grow memory).
CLIENT_QUEUE = 200
# Largest request body accepted (bytes): a TLX answer is ~150.
MAX_BODY = 10_000
# Host names every request may name besides the served address (loopback only).
LOOPBACK_NAMES = ('127.0.0.1', 'localhost', '[::1]')
# The header that carries the session's secret, and the placeholder the pages hold for it.
TOKEN_HEADER = 'X-HRC-Token'
TOKEN_PLACEHOLDER = b'__HRC_SESSION_TOKEN__'


def host_name(host_header: str) -> str:
    """Return the host name of a ``Host`` header without the port, lower case."""
    host = host_header.strip().lower()
    if host.startswith('['):                    # [::1]:8765
        return host[:host.find(']') + 1] if ']' in host else host
    return host.rsplit(':', 1)[0] if ':' in host else host


class RequestGuard:
    """Decides whether a request comes from the lab's own page (pure: headers in, reason out).

    ``address`` and ``port`` are where the pages are served; ``token`` the session's secret.
    """

    def __init__(self, address: str, port: int, token: str):
        self.port = port
        self.token = token
        self.hosts = {name.lower() for name in LOOPBACK_NAMES + (address,)}
        self.origins = {f'http://{host}:{port}' for host in self.hosts}

    def refusal(self, method: str, headers) -> str:
        """Return why the request must be refused ('' = it may go on)."""
        host = headers.get('Host')
        if not host:
            return 'no Host header'
        if host_name(host) not in self.hosts:
            return f'foreign Host {host!r}'
        if method == 'GET':
            return ''
        origin = headers.get('Origin')
        if not origin:
            return 'no Origin header on a state-changing request'
        if origin.lower() not in self.origins:
            return f'foreign Origin {origin!r}'
        offered = headers.get(TOKEN_HEADER) or ''
        if not secrets.compare_digest(offered.encode(), self.token.encode()):
            return f'missing or wrong {TOKEN_HEADER} (the session secret of the served page)'
        return ''


def state_view(message: TaskState) -> StateView:
    """Convert a TaskState."""
    return StateView(int(message.episode), int(message.step), float(message.slider_position),
                     float(message.pendulum_angle), float(message.ball_position),
                     bool(message.truncated or message.terminated),
                     float(message.slider_velocity), float(message.pendulum_angular_velocity),
                     float(message.ball_velocity), bool(message.human_command_missing),
                     bool(message.robot_command_missing))


def session_view(message: SessionStatus) -> SessionView:
    """Convert a SessionStatus."""
    return SessionView(message.session_id, int(message.case_id), message.strategy,
                       int(message.training_step), int(message.training_step_count),
                       dof_name(message.human_dof, ''), bool(message.human_involved),
                       tuple(message.human_subtasks), int(message.episode),
                       int(message.total_episodes), int(message.human_involved_episodes),
                       phase_label(message.phase, f'phase {message.phase}'), message.message)


def result_view(message: EpisodeSummary) -> ResultView:
    """Convert an EpisodeSummary."""
    return ResultView(int(message.episode), bool(message.evaluation),
                      bool(message.human_involved), float(message.slider_error),
                      float(message.pendulum_error), float(message.ball_error),
                      float(message.total_error), bool(message.converged))


def human_view(message: HumanAction, now: float) -> HumanView:
    """Convert a HumanAction."""
    source = SOURCE_NAMES[message.source] if message.source < len(SOURCE_NAMES) else '?'
    return HumanView(source, message.source_detail, bool(message.engaged),
                     float(message.command), now)


def event_bytes(name: str, document) -> bytes:
    """Return one Server-Sent Event (strict JSON: no NaN)."""
    return f'event: {name}\ndata: {json.dumps(document, allow_nan=False)}\n\n'.encode()


class EventHub:
    """Fan-out of server-sent events to every connected page; the newest of each kept."""

    KEPT = ('geometry', 'words', 'console', 'tlx')   # sent to a page as soon as it connects

    def __init__(self):
        self._lock = threading.Lock()
        self._clients = []
        self._latest = {}

    def publish(self, name: str, document) -> None:
        """Send an event to every client (a full client queue drops its oldest event)."""
        data = event_bytes(name, document)
        with self._lock:
            if name in self.KEPT:
                self._latest[name] = data
            clients = list(self._clients)
        for client in clients:
            try:
                client.put_nowait(data)
            except queue.Full:
                try:
                    client.get_nowait()
                    client.put_nowait(data)
                except (queue.Empty, queue.Full):
                    pass

    def connect(self) -> queue.Queue:
        """Return a new client queue, primed with the newest kept events."""
        client = queue.Queue(CLIENT_QUEUE)
        with self._lock:
            for name in self.KEPT:
                if name in self._latest:
                    client.put_nowait(self._latest[name])
            self._clients.append(client)
        return client

    def disconnect(self, client) -> None:
        """Forget a client."""
        with self._lock:
            if client in self._clients:
                self._clients.remove(client)

    @property
    def client_count(self) -> int:
        """Return the number of connected pages."""
        with self._lock:
            return len(self._clients)


class PageServer:
    """The HTTP side: files, the event stream, status.json, the controls and the TLX form."""

    def __init__(self, node: 'DisplayNode', port: int):
        self.node = node
        self.closing = threading.Event()
        server = self

        class Handler(http.server.BaseHTTPRequestHandler):
            protocol_version = 'HTTP/1.1'

            def do_GET(self):  # noqa: N802 (the name http.server calls)
                server.get(self)

            def do_POST(self):  # noqa: N802
                server.post(self)

            def do_PUT(self):  # noqa: N802 (any other method: 405, after the guard)
                server.other(self)

            do_DELETE = do_PATCH = do_OPTIONS = do_PUT  # noqa: N815

            def log_message(self, format, *args):  # noqa: A002
                pass  # one line per request would flood the log

        class Server(http.server.ThreadingHTTPServer):
            def handle_error(self, request, client_address):
                # One line, never a traceback in the display's log (the request is dropped).
                error = sys.exc_info()[1]
                server.node.get_logger().warning(
                    f'request from {client_address[0]} dropped: {type(error).__name__}: '
                    f'{error}', throttle_duration_sec=5.0)

        self.httpd = Server(('127.0.0.1', port), Handler)
        self.httpd.daemon_threads = True
        self.address, self.port = self.httpd.server_address[:2]
        self.token = secrets.token_urlsafe(24)
        self.guard = RequestGuard(self.address, self.port, self.token)
        self.thread = threading.Thread(target=self.httpd.serve_forever, name='display-http',
                                       daemon=True)
        self.thread.start()

    @staticmethod
    def answer(request, code: int, body: bytes, content_type: str) -> None:
        """Send a whole answer."""
        request.send_response(code)
        request.send_header('Content-Type', content_type)
        request.send_header('Content-Length', str(len(body)))
        request.send_header('Cache-Control', 'no-store')
        request.end_headers()
        request.wfile.write(body)

    def refused(self, request, method: str) -> bool:
        """Answer 403 and log it when the request is not from the lab's page; say if so."""
        reason = self.guard.refusal(method, request.headers)
        if not reason:
            return False
        path = request.path.split('?', 1)[0]
        self.node.get_logger().warning(
            f'refused {method} {path[:80]} from {request.client_address[0]}: {reason}')
        try:
            self.answer(request, 403, f'refused: {reason}'.encode(), 'text/plain; charset=utf-8')
        except OSError:
            pass
        return True

    def other(self, request) -> None:
        """Answer a method the server does not offer (after the guard)."""
        if not self.refused(request, request.command):
            self.answer(request, 405, b'GET or POST only', 'text/plain; charset=utf-8')

    def get(self, request) -> None:
        """Answer one GET request."""
        path = request.path.split('?', 1)[0]
        if self.refused(request, 'GET'):
            return
        try:
            if path in FILES:
                name, content_type = FILES[path]
                body = (WEB / name).read_bytes().replace(TOKEN_PLACEHOLDER,
                                                         self.token.encode())
                self.answer(request, 200, body, content_type)
            elif path == '/events':
                self.stream(request)
            elif path == '/status.json':
                body = json.dumps(self.node.status(), indent=1, allow_nan=False).encode()
                self.answer(request, 200, body, 'application/json')
            else:
                self.answer(request, 404, b'not here: try /, /console or /status.json',
                            'text/plain; charset=utf-8')
        except (BrokenPipeError, ConnectionResetError):
            pass  # the browser went away mid-answer
        except Exception as error:  # a bug must not kill the server thread; say it plainly
            self.node.get_logger().error(f'GET {path} failed: {type(error).__name__}: {error}',
                                         throttle_duration_sec=5.0)
            try:
                self.answer(request, 503, f'the display could not answer: {error}'.encode(),
                            'text/plain; charset=utf-8')
            except OSError:
                pass

    def stream(self, request) -> None:
        """Push the events to one page until it goes away."""
        request.send_response(200)
        request.send_header('Content-Type', 'text/event-stream')
        request.send_header('Cache-Control', 'no-store')
        request.send_header('Connection', 'keep-alive')
        request.end_headers()
        client = self.node.hub.connect()
        try:
            request.wfile.write(b'retry: 1000\n\n')
            request.wfile.flush()
            while not self.closing.is_set():
                try:
                    data = client.get(timeout=1.0)
                except queue.Empty:
                    data = b': keep-alive\n\n'
                request.wfile.write(data)
                request.wfile.flush()
        finally:
            self.node.hub.disconnect(client)

    def post(self, request) -> None:
        """Answer one POST request: a control button or the TLX form."""
        path = request.path.split('?', 1)[0]
        text_plain = 'text/plain; charset=utf-8'
        try:
            length = int(request.headers.get('Content-Length') or 0)
        except ValueError:
            length = -1
        try:
            if length < 0:
                request.close_connection = True
                self.answer(request, 400, b'bad Content-Length', text_plain)
                return
            if length > MAX_BODY:
                request.close_connection = True
                self.answer(request, 413, f'body over {MAX_BODY} bytes'.encode(), text_plain)
                return
            if self.refused(request, 'POST'):
                request.close_connection = True
                return
            body = request.rfile.read(length) if length else b''
            if path.startswith('/control/') and path[len('/control/'):] in OPERATOR_SERVICES:
                code, text = self.node.control(path[len('/control/'):])
            elif path == '/tlx':
                code, text = self.node.store_tlx(body)
            else:
                code, text = 404, 'not here: POST /control/<pause|resume|abort> or /tlx'
            self.answer(request, code, text.encode(), text_plain)
        except (BrokenPipeError, ConnectionResetError):
            pass
        except Exception as error:  # a bug must not kill the server thread; say it plainly
            self.node.get_logger().error(f'POST {path} failed: {type(error).__name__}: {error}',
                                         throttle_duration_sec=5.0)
            try:
                self.answer(request, 503, f'the display could not answer: {error}'.encode(),
                            text_plain)
            except OSError:
                pass

    def close(self) -> None:
        """Stop serving and release the port."""
        self.closing.set()
        self.httpd.shutdown()
        self.httpd.server_close()


class DisplayNode(Node):
    """Feeds a DisplayModel from the topics and serves the pages (see the module docstring)."""

    def __init__(self):
        super().__init__('display')
        self.params = params = declare_parameters(self, DisplayParams)
        self.model = DisplayModel()
        self.hub = EventHub()
        self.create_subscription(TaskState, topics.STATE, self.on_state, qos.STATE_QOS)
        # At the human's rate the sim also publishes the states within each period: the
        # page's picture follows them (the session's counters and errors use /hrc/state).
        self.create_subscription(TaskState, topics.SLICE_STATE, self.on_slice_state,
                                 qos.STATE_QOS)
        self.create_subscription(SessionStatus, topics.SESSION, self.on_session,
                                 qos.SESSION_QOS)
        self.create_subscription(EpisodeSummary, topics.EPISODE, self.on_episode,
                                 qos.EPISODE_QOS)
        self.create_subscription(HumanAction, topics.HUMAN_ACTION, self.on_human,
                                 qos.HUMAN_ACTION_QOS)
        self.create_subscription(String, INPUT_LOST_TOPIC, self.on_input_lost,
                                 qos.SESSION_QOS)
        self.controls = {command: self.create_client(Trigger, service)
                         for command, service in OPERATOR_SERVICES.items()}
        self.sim_query = ParameterQuery(self, params.sim_node, SIM_PARAMETERS, self.on_sim)
        self.agent_query = ParameterQuery(self, params.agent_node, AGENT_PARAMETERS,
                                          self.on_agent)
        self.create_timer(params.query_period, self.poll_queries)
        self.create_timer(1.0 / params.words_rate, self.push_words)
        self.session_id = None
        self.tlx_stored = set()       # session ids whose questionnaire was answered
        self._pushed = {}             # event name -> the JSON last pushed
        self.hub.publish('geometry', scene_geometry(PhysicsParams()))
        try:
            self.server = PageServer(self, params.port)
        except OSError as error:
            raise ParameterError(f'DisplayParams rejected: port: cannot serve on '
                                 f'127.0.0.1:{params.port}: {error.strerror}') from None
        self.get_logger().info(
            f"serving the display on http://127.0.0.1:{self.server.port}/ (the person's "
            f'page) and http://127.0.0.1:{self.server.port}/console (the experimenter); '
            f'geometry from /{params.sim_node}, episodes from /{params.agent_node}')

    # ------------------------------------------------------------------ inputs

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
        self.hub.publish('geometry', scene_geometry(physics))
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
        """Take a new state and push it to the pages at once."""
        state = state_view(message)
        self.model.on_state(state, time.monotonic())
        self.hub.publish('state', state_document(state, time.time() * 1000.0))

    def on_slice_state(self, message: TaskState):
        """Push a state within a period (the human's rate) to the pages' picture only."""
        state = state_view(message)
        if state.finite():
            self.hub.publish('state', state_document(state, time.time() * 1000.0))

    def on_session(self, message: SessionStatus):
        """Take a new session status; a new session id means a new agent: ask it again."""
        if message.session_id != self.session_id:
            if self.session_id is not None:
                self.agent_query.restart()
                self.sim_query.restart()
            self.session_id = message.session_id
            if self.params.tlx_file:     # answered before this display started: not asked again
                self.tlx_stored |= {item.get('session_id') for item in self.tlx_answers()}
            self.get_logger().info(f'showing session {message.session_id!r} (case '
                                   f'{message.case_id}, {message.strategy})')
        self.model.on_session(session_view(message), time.monotonic())
        self.push_words()

    def on_episode(self, message: EpisodeSummary):
        """Take the summary of a finished episode."""
        self.model.on_result(result_view(message), time.monotonic())

    def on_human(self, message: HumanAction):
        """Take the newest human action (its source and health)."""
        self.model.on_human(human_view(message, time.monotonic()))

    def on_input_lost(self, message: String):
        """Take the session runner's word that the person's input is lost ('' = back)."""
        self.model.set_input_lost(message.data)
        self.push_words()

    # ------------------------------------------------------------------ outputs

    def push_words(self):
        """Recompute the words, the console and the TLX request; push what changed."""
        snapshot = self.model.snapshot(time.monotonic())
        words = overlay(snapshot, self.params.result_seconds)
        session = snapshot.session
        wanted = bool(self.params.tlx_file and session is not None and session.phase == 'done'
                      and session.session_id not in self.tlx_stored)
        documents = {'words': overlay_document(words), 'console': console_document(snapshot),
                     'tlx': {'wanted': wanted, 'condition': session.session_id if session
                             else '', 'title': self.params.tlx_title}}
        for name, document in documents.items():
            text = json.dumps(document, sort_keys=True)
            if self._pushed.get(name) != text:
                self._pushed[name] = text
                self.hub.publish(name, document)

    def status(self) -> dict:
        """Return the /status.json document."""
        snapshot = self.model.snapshot(time.monotonic())
        document = status_document(snapshot, overlay(snapshot, self.params.result_seconds))
        document['pages_connected'] = self.hub.client_count
        return document

    def control(self, command: str, timeout: float = 10.0):
        """Call the agent's operator service ``command``; return (HTTP code, answer)."""
        client = self.controls[command]
        if not client.wait_for_service(timeout_sec=2.0):
            return 503, (f'{command}: no agent serves {OPERATOR_SERVICES[command]}: is the '
                         f'session running?')
        done = threading.Event()
        future = client.call_async(Trigger.Request())
        future.add_done_callback(lambda _: done.set())
        if not done.wait(timeout):
            return 504, f'{command}: no answer from the agent within {timeout:.0f} s'
        response = future.result()
        self.get_logger().info(f'console {command}: {response.message}')
        if not response.success:
            return 409, f'{command} refused: {response.message}'
        return 200, f'{command}: {response.message}'

    def tlx_answers(self) -> list:
        """Return the answers stored in ``tlx_file`` ([] when none or unreadable)."""
        path = pathlib.Path(self.params.tlx_file)
        try:
            document = yaml.safe_load(path.read_text()) if path.is_file() else []
        except (OSError, yaml.YAMLError, UnicodeDecodeError):
            return []
        return [item for item in document or [] if isinstance(item, dict)]

    def store_tlx(self, body: bytes):
        """Check and append one raw NASA-TLX answer; return (HTTP code, answer).

        Accepted only for the condition the page asks about now (its session is done and
        the page showed the form), on the form's grid, every scale answered; a second answer
        for the same condition only when it says ``"correction": true`` (stored as one).
        """
        if not self.params.tlx_file:
            return 404, 'no questionnaire in this session (tlx_file is empty)'
        try:
            answer = json.loads(body or b'{}')
        except (ValueError, UnicodeDecodeError):
            return 400, 'not JSON'
        scores, reasons = check_tlx(answer, step=TLX_STEP)
        if reasons:
            return 400, 'rejected: ' + '; '.join(reasons)
        session = self.model.snapshot(time.monotonic()).session
        if session is None or session.phase != 'done':
            phase = session.phase if session else 'no session yet'
            return 409, (f'rejected: the questionnaire is asked at the end of the condition '
                         f'(now: {phase})')
        if answer.get('condition') != session.session_id:
            return 409, (f'rejected: the page asked about {session.session_id!r}, not '
                         f'{answer.get("condition")!r}')
        existing = self.tlx_answers()
        earlier = [item for item in existing if item.get('session_id') == session.session_id]
        correction = answer.get('correction') is True
        if earlier and not correction:
            return 409, (f'rejected: this condition was answered at '
                         f'{earlier[-1].get("answered")}; a second answer must be sent as a '
                         f'correction ("correction": true)')
        record = {'session_id': session.session_id, 'case': session.case_id,
                  'answered': datetime.datetime.now().isoformat(timespec='seconds'),
                  'scales': scores, 'raw_tlx': round(raw_tlx(scores), 2)}
        if earlier:
            record.update(correction=True, corrects=earlier[-1].get('answered'))
        path = pathlib.Path(self.params.tlx_file)
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(path, yaml.safe_dump(existing + [record], sort_keys=False),
                     mode=PERSONAL_FILE_MODE)
        os.chmod(path, PERSONAL_FILE_MODE)
        self.tlx_stored.add(record['session_id'])
        self.get_logger().info(f'NASA-TLX {"correction " if earlier else ""}stored in {path}: '
                               f'raw TLX {record["raw_tlx"]}')
        self.push_words()
        return 200, f'Thank you. Stored (raw TLX {record["raw_tlx"]}).'

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
