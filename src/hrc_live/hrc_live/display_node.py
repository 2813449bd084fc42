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

Only the lab's own pages may act (``RequestGuard``; it, the HTTP side ``PageServer`` and the
event fan-out ``EventHub`` are in ``hrc_live.page_server``): every request must name a loopback
host or the served address in ``Host`` (a DNS-rebinding site cannot even read
``/status.json``); every ``POST`` must come from the server's own origin (``Origin``) and carry
the session's secret in the ``X-HRC-Token`` header, a random token written into the pages when
they are served (never in a URL, so never in a log). Anything else is refused with 403 and
logged. A malformed request (a bad ``Content-Length``) is answered 400; a body over
``MAX_BODY`` bytes 413.

The geometry and timing come from the sim's own parameters and the episode counts and break
from the agent's, asked through their parameter services (``sim_node``, ``agent_node``), so
nothing is configured twice. A lost input of the person (``input_lost_topic``, set by the
session runner) shows "joystick disconnected" on both pages.
"""

from dataclasses import fields
import datetime
import json
import os
import pathlib
import threading
import time

from hrc_common import bounded_yaml
from hrc_common import qos, topics
from hrc_common.contract import atomic_write, dof_name, PERSONAL_FILE_MODE, phase_label
from hrc_common.diagnostics import DIAGNOSTICS_TOPIC
from hrc_common.nodes import run_node
from hrc_common.parameter_query import ParameterQuery
from hrc_common.params import declare_parameters, ParameterError, with_overrides
from hrc_common.session_control import OPERATOR_SERVICES
from hrc_common.tlx import check_tlx, raw_tlx, TLX_STEP
from diagnostic_msgs.msg import DiagnosticArray
from hrc_msgs.msg import EpisodeSummary, HumanAction, SessionStatus, TaskState
from hrc_sim_node.physics import PhysicsParams
from rclpy.node import Node
from sensor_msgs.msg import Joy
from std_msgs.msg import String
from std_srvs.srv import Trigger
import yaml

from hrc_live.display_core import (AgentPlan, DisplayModel, HumanView, ResultView, SessionView,
                                   SOURCE_NAMES, StateView)
from hrc_live.display_documents import (console_document, overlay_document, scene_geometry,
                                        state_document, status_document)
from hrc_live.display_words import overlay, SteadyBanner
from hrc_live.display_params import DisplayParams
from hrc_live.gamepad import gamepad_body, joy_values
from hrc_live.input_check import INPUT_LOST_TOPIC
from hrc_live.page_server import EventHub, PageServer, tlx_body

SUMMARY = ("The pages of a live hrc session on http://127.0.0.1:<port>/: the person's page "
           '(scene drawn in the browser from a pushed state stream) and /console for the '
           'experimenter (input health, errors, pause/resume/abort).')

# The sim's parameters the drawing needs, and the agent's the overlay needs.
SIM_PARAMETERS = ('rod_length', 'pendulum_length', 'ball_radius', 'pendulum_limit',
                  'control_period', 'episode_duration')
# s: a page's gamepad silent this long is gone (unplugged, the page closed): its /joy writer is
# withdrawn. The page sends at least every 50 ms while one is connected.
GAMEPAD_SILENCE_S = 0.5
AGENT_PARAMETERS = ('max_training_episodes', 'evaluation_episodes', 'episode_break', 'mode')


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
        self.create_subscription(String, topics.RUNNER_WAITING, self.on_runner_waiting,
                                 qos.SESSION_QOS)
        self.create_subscription(String, topics.REPLAY, self.on_replay, qos.SESSION_QOS)
        # every node's health, as ROS tools read it (the console's "Health" table)
        self.create_subscription(DiagnosticArray, DIAGNOSTICS_TOPIC, self.on_diagnostics, 10)
        self.controls = {command: self.create_client(Trigger, service)
                         for command, service in OPERATOR_SERVICES.items()}
        self.sim_query = ParameterQuery(self, params.sim_node, SIM_PARAMETERS, self.on_sim)
        self.agent_query = ParameterQuery(self, params.agent_node, AGENT_PARAMETERS,
                                          self.on_agent)
        self.create_timer(params.query_period, self.poll_queries)
        self.create_timer(1.0 / params.words_rate, self.push_words)
        # the person's gamepad from the page (hrc_live.gamepad): a /joy writer while it sends
        self.joy_pub, self.gamepad_at, self.gamepad_name = None, 0.0, ''
        self._gamepad_lock = threading.Lock()
        if params.gamepad:
            self.create_timer(GAMEPAD_SILENCE_S / 2, self.drop_silent_gamepad)
        self.session_id = None
        self.tlx_stored = set()       # session ids whose questionnaire was answered
        self.tlx_saved = {}           # session id -> (time, raw TLX) stored by this display
        self._pushed = {}             # event name -> the JSON last pushed
        self.steady = SteadyBanner()  # no banner flickers on the person's page
        self._push_lock = threading.Lock()  # the timer and a TLX answer (HTTP thread) push
        self.words = None             # the words last pushed (status.json shows the same)
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

    def on_diagnostics(self, message: DiagnosticArray):
        """Keep each node's newest status for the console."""
        now = time.monotonic()
        for status in message.status:      # level: a byte (OK 0, WARN 1, ERROR 2, STALE 3)
            self.model.set_health(status.name, status.level[0], status.message, now)

    def on_input_lost(self, message: String):
        """Take the session runner's word that the person's input is lost ('' = back)."""
        self.model.set_input_lost(message.data)
        self.push_words()

    def on_runner_waiting(self, message: String):
        """Take the session runner's word on why it waits ('' = it does not)."""
        self.model.set_runner_waiting(message.data)
        self.push_words()

    def on_replay(self, message: String):
        """Take a replay node's word on what it replays ('' = the replay ended)."""
        self.model.set_replay(message.data)
        self.push_words()

    # ------------------------------------------------------------------ outputs

    def push_words(self):
        """Recompute the words, the console and the TLX request; push what changed."""
        with self._push_lock:
            self._push_words()

    def _push_words(self):
        now = time.monotonic()
        snapshot = self.model.snapshot(now)
        words = self.words = self.steady.shown(overlay(snapshot, self.params.result_seconds),
                                               now)
        session = snapshot.session
        wanted = bool(self.params.tlx_file and session is not None and session.phase == 'done'
                      and session.session_id not in self.tlx_stored)
        documents = {'words': overlay_document(words),
                     'console': console_document(snapshot, self.study(),
                                                 self.tlx_status(session)),
                     'tlx': {'wanted': wanted, 'condition': session.session_id if session
                             else '', 'title': self.params.tlx_title}}
        for name, document in documents.items():
            text = json.dumps(document, sort_keys=True)
            if self._pushed.get(name) != text:
                self._pushed[name] = text
                self.hub.publish(name, document)

    def study(self) -> dict:
        """Return the subject and condition the console shows (empty without a subject)."""
        if not self.params.subject_id:
            return {}
        return {'subject_id': self.params.subject_id, 'condition': self.params.condition}

    def tlx_status(self, session) -> str:
        """Return where the NASA-TLX of the shown condition is, for the console."""
        if not self.params.tlx_file:
            return 'not asked in this session (no --tlx)'
        if session is None or session.phase != 'done':
            return "asked on the person's page when the condition ends"
        stored = self.tlx_saved.get(session.session_id)
        if stored is None and session.session_id in self.tlx_stored:
            return 'stored earlier'
        if stored is None:
            return "waiting for the person's answers on the page"
        return f'stored at {stored[0]} (raw TLX {stored[1]})'

    def status(self) -> dict:
        """Return the /status.json document."""
        snapshot = self.model.snapshot(time.monotonic())
        words = self.words or overlay(snapshot, self.params.result_seconds)
        document = status_document(snapshot, words)
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
            document = bounded_yaml.load_file(path) if path.is_file() else []
        except (OSError, yaml.YAMLError, UnicodeDecodeError):
            return []
        return [item for item in document or [] if isinstance(item, dict)]

    def store_gamepad(self, body: bytes):
        """Publish one reading of the page's gamepad on /joy; return (HTTP code, answer)."""
        if not self.params.gamepad:
            return 404, 'no gamepad in this session (display parameter gamepad is false)'
        record, problem = gamepad_body(body)
        if problem:
            return 400, problem
        axes, buttons = joy_values(record)
        message = Joy(axes=axes, buttons=buttons)
        message.header.stamp = self.get_clock().now().to_msg()
        name = f"{record.get('id', '') or 'a gamepad'}, axis {record.get('axis_index', 0)}"
        with self._gamepad_lock:
            if self.joy_pub is None:
                self.joy_pub = self.create_publisher(Joy, topics.JOY, qos.JOY_QOS)
            if name != self.gamepad_name:
                self.get_logger().info(f"the person's gamepad ({name}) drives {topics.JOY}")
                self.gamepad_name = name
            self.gamepad_at = time.monotonic()
            self.joy_pub.publish(message)
        return 200, 'ok'

    def drop_silent_gamepad(self) -> None:
        """Withdraw the /joy writer when the page's gamepad fell silent (unplugged, closed)."""
        with self._gamepad_lock:
            if self.joy_pub is None or time.monotonic() - self.gamepad_at < GAMEPAD_SILENCE_S:
                return
            self.destroy_publisher(self.joy_pub)
            self.joy_pub, self.gamepad_name = None, ''
        self.get_logger().warning(f"the person's gamepad is silent: {topics.JOY} withdrawn")

    def store_tlx(self, body: bytes):
        """Check and append one raw NASA-TLX answer; return (HTTP code, answer).

        Accepted only for the condition the page asks about now (its session is done and
        the page showed the form), on the form's grid, every scale answered; a second answer
        for the same condition only when it says ``"correction": true`` (stored as one).
        """
        if not self.params.tlx_file:
            return 404, 'no questionnaire in this session (tlx_file is empty)'
        answer, problem = tlx_body(body)
        if problem:
            return 400, problem
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
        self.tlx_saved[record['session_id']] = (record['answered'][11:], record['raw_tlx'])
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
