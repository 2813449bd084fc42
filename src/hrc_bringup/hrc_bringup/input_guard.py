"""The input guard of a session with a person: pause at once when their input is lost.

Never a silent stand-in: in realtime with ``--human device``, ``joy`` or ``auto`` the runner
does not start until the input is there (:func:`wait_for_input` lists the joystick devices it
sees and how to fix it); the human node holds zero and asks to pause when its input is lost
(``on_input_lost: pause``, its ``/hrc/human/input`` status) and :class:`InputGuard` then pauses
the session at once: the agent holds it in its own process (zero commands, the running episode
dropped, the sim holds, phase paused; the page, the console and ``hrc operator status`` say
"joystick disconnected", and "connected again" as soon as the human node reports it back);
the agent refuses the operator's resume until then, and runs the interrupted episode again
(``hrc_agent_node.agent_input_hold``).
"""

import sys
import time

from diagnostic_msgs.msg import DiagnosticStatus
from hrc_common import qos, topics
from hrc_common.contract import ACTIVE_PHASES, Phase
from hrc_common.session_control import LOST_INPUT_WORDS, STOP_FOR_INPUT_SERVICE
from hrc_live.input_check import (device_missing_message, device_presence, INPUT_LOST_TOPIC,
                                  joy_missing_message, joystick_devices, lost_reason)
from hrc_msgs.msg import HumanAction, SessionStatus, TaskState
from std_msgs.msg import String
from std_srvs.srv import Trigger

# Link watchdog: a gap between states longer than this (s) is a break or a pause, not a loss;
# the human node's input status comes at least every second, so this long without it (s) means
# its station is unreachable.
STATE_GAP_S = 0.5
STATUS_SILENCE_S = 2.5


class InputGuard:
    """Pauses the session at once when the person's input is lost; resumes on the operator's word.

    Watches ``/hrc/human/action``: an answer holding zero because the input is lost
    (:func:`hrc_live.input_check.lost_reason`) while the person is involved makes the runner
    say "joystick disconnected" on ``/hrc/session/input_lost`` (the pages, the agent) and ask
    the agent to hold (``/hrc/agent/stop_for_input``); ``input_lost`` is cleared as soon as the
    human node reports the input back. The agent, the one writer of ``/hrc/session``, says the
    pause and takes the operator's resume; the loss ends when its status runs again.
    """

    def __init__(self, node, kind: str, device: str, link_timeout: float = 1.0):
        self.node, self.kind, self.device = node, kind, device
        self.lost = ''                  # why the session is paused for a lost input ('' = not)
        self.back = False               # paused for a lost input that is there again
        # The link watchdog (two hosts, docs/two_hosts.md): monotonic s of the newest state,
        # of the newest answer from the person's side and of the human node's newest status.
        self.link_timeout = link_timeout
        self.last_state_at = self.last_action_at = self.input_status_at = None
        self.states_flow_since = None   # states run again after a gap (break, pause) since
        self.involved = False           # the person acts in the current training step
        self.held = False               # the agent has said it holds for the loss
        self.last_status = None
        self._practice_told = False
        self._waiting_pub = None        # /hrc/session/runner_waiting: one writer, made once
        self._string = String
        self._trigger = Trigger
        self._topics, self._qos = topics, qos
        self.lost_pub = node.create_publisher(String, INPUT_LOST_TOPIC, qos.SESSION_QOS)
        self.lost_pub.publish(String(data=''))
        self.abort_client = node.create_client(Trigger, STOP_FOR_INPUT_SERVICE)
        node.create_subscription(HumanAction, topics.HUMAN_ACTION, self._on_action,
                                 qos.HUMAN_ACTION_QOS)
        node.create_subscription(TaskState, topics.STATE, self._on_state, qos.STATE_QOS)
        node.create_subscription(SessionStatus, topics.SESSION, self._on_status,
                                 qos.SESSION_QOS)
        # The human node's input status (src/hrc_joystick_node/README.md): pause_requested
        # when its joystick is missing or lost, state 'ok' when it is back.
        self.input_status = {}          # the newest status's key-values, plus 'message'
        node.create_subscription(DiagnosticStatus, topics.HUMAN_INPUT, self._on_input_status,
                                 qos.SESSION_QOS)

    def present(self) -> tuple:
        """Return (present, why) of the person's input now.

        The human node's word when it has spoken (its input status), else the runner's own
        look at the device or at /joy's publishers (before the human node runs).
        """
        if self.input_status:
            silent = time.monotonic() - self.input_status_at
            if silent > STATUS_SILENCE_S:   # it speaks at least every second when reachable
                return False, (f'no word from the human node for {silent:.1f} s: the network '
                               f"link to the person's station or the human node is down")
            ok = self.input_status.get('state') == 'ok'
            return ok, self.input_status.get('message', '')
        present, why = device_presence(self.device)
        if self.kind == 'device' or present:
            return present, why if present else device_missing_message(
                self.device, why, joystick_devices())
        publishers = self.node.count_publishers(self._topics.JOY)
        if publishers:
            return True, f'/joy has {publishers} publisher{"s" if publishers > 1 else ""}'
        if self.kind == 'joy':
            return False, joy_missing_message(publishers)
        return False, (device_missing_message(self.device, why, joystick_devices()) + ' Or: '
                       + joy_missing_message(publishers))

    def say_waiting(self, reason: str) -> None:
        """Say on /hrc/session/runner_waiting why the runner waits ('' = it does not)."""
        if self._waiting_pub is None:
            self._waiting_pub = self.node.create_publisher(self._string, topics.RUNNER_WAITING,
                                                           qos.SESSION_QOS)
        self._waiting_pub.publish(self._string(data=reason))

    def _on_status(self, status):
        self.last_status = status
        if status.human_involved and not self.involved:
            # The person's side sends nothing while the robot learns alone: the silence
            # the link watchdog measures starts when the person joins, not before.
            self.states_flow_since = time.monotonic()
        self.involved = bool(status.human_involved)
        if self.lost:
            if status.phase == Phase.PAUSED:
                self.held = True
            elif self.held and status.phase in ACTIVE_PHASES:
                self._clear_loss()      # the operator's resume: the agent runs on
        # The person's step begins while their input is already gone: pause now.
        elif self.involved and self.input_status.get('pause_requested') == 'true':
            self._lose(self.input_status.get('message') or 'the human node asks to pause')

    def _on_input_status(self, status):
        values = {item.key: item.value for item in status.values}
        values['message'] = status.message
        self.input_status = values
        self.input_status_at = time.monotonic()
        if self.lost:
            self._say_back(values.get('state') == 'ok', status.message)
        elif values.get('pause_requested') == 'true' and self.involved:
            self._lose(status.message or 'the human node asks to pause')

    def _say_back(self, present: bool, message: str) -> None:
        """While paused for a lost input, say at once when it is back (or lost again).

        The pages, the console and ``operator status`` read "connected again" from the cleared
        ``/hrc/session/input_lost`` and the paused status's message as soon as the human node
        reports the input back, not only after the operator's resume.
        """
        if present == self.back:
            return
        self.back = present
        if present:
            print(f'[session] the joystick is connected again ({message}): resume with '
                  f'"hrc operator resume" or the console', flush=True)
        else:
            print(f'[session] the joystick is disconnected again: {message}', flush=True)
        self.lost_pub.publish(self._string(data='' if present else self.lost))

    def _on_state(self, state):
        now = time.monotonic()
        if self.last_state_at is None or now - self.last_state_at > STATE_GAP_S:
            self.states_flow_since = now
        self.last_state_at = now

    def _on_action(self, action):
        self.last_action_at = time.monotonic()
        reason = lost_reason(action.source, action.source_detail, self.involved)
        if reason:
            self._lose(reason)

    def _lose(self, reason: str) -> None:
        """Pause the session at once: the person's input is lost while they act."""
        if self.lost or (self.last_status is not None
                         and self.last_status.phase not in ACTIVE_PHASES):
            return  # already paused, or nothing runs (done, aborted, paused by the operator)
        if self.last_status is not None and self.last_status.strategy == 'practice':
            if not self._practice_told:  # nothing learned to protect: say it, the human node
                #                              holds 0 and the agent's practice goes on
                self._practice_told = True
                print(f'[session] practice: {reason}; the human node holds zero, the practice '
                      f'goes on', flush=True)
            return
        if not reason.startswith(LOST_INPUT_WORDS):
            reason = f'{LOST_INPUT_WORDS}: {reason}'
        self.lost = reason
        print(f'[session] {reason}: pausing the session now (the agent holds it: the running '
              f'episode dropped, the sim holds, zero commands); resume with "hrc operator '
              f'resume" or the console once it is back', flush=True)
        self.lost_pub.publish(self._string(data=reason))
        if self.abort_client.service_is_ready():
            self.abort_client.call_async(self._trigger.Request())

    def _clear_loss(self) -> None:
        print('[session] resumed by the operator: the agent goes on in its process (the '
              'interrupted episode runs again)', flush=True)
        self.lost, self.held, self.back = '', False, False
        self.lost_pub.publish(self._string(data=''))

    def watch_link(self) -> None:
        """Pause when states run but the person's side has not answered for link_timeout s.

        Over two hosts a dropped network link silences the human node without any word from
        it; the sim then counts the person's commands missing. That is a lost input like an
        unplugged joystick: pause the same way, and resume only on the operator's word.
        """
        now = time.monotonic()
        if (not self.involved or self.lost or self.last_status is None
                or self.last_status.phase not in (Phase.TRAINING, Phase.EVALUATION)
                or self.last_state_at is None or now - self.last_state_at > STATE_GAP_S):
            return      # nothing runs now, or the person does not act, or already paused
        since = now - max(self.last_action_at or 0.0, self.states_flow_since)
        if since > self.link_timeout:
            self._lose(f"no answer from the person's side for {since:.1f} s while the "
                       f'episode runs (network link to the station or human node down)')

    def tick(self) -> None:
        """Watch the link to the person's side (two hosts)."""
        self.watch_link()


def wait_for_input(guard: InputGuard, executor, timeout: float, stop_reason: list) -> bool:
    """Wait until the person's input is there; say what is missing and how to fix it.

    Said on the terminal and on ``/hrc/session/runner_waiting`` (the console shows it; the
    person's page only asks them to wait); cleared when the wait ends.
    """
    deadline = time.monotonic() + timeout
    said = ''
    while True:
        present, why = guard.present()
        if present:
            if said:
                print(f'[session] the input is there now: {why}', flush=True)
                guard.say_waiting('')
            return True
        if why != said:
            print(f"[session] waiting for the person's input (up to {timeout:.0f} s): {why}",
                  flush=True)
            guard.say_waiting(f"waiting for the person's input (up to {timeout:.0f} s): {why}")
            said = why
        if time.monotonic() > deadline or stop_reason:
            print(f'[session] not started: {why}', file=sys.stderr, flush=True)
            guard.say_waiting(f'not started: {why}')
            return False
        executor.spin_once(timeout_sec=0.2)
