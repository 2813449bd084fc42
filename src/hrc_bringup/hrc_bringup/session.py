"""Session runner: start the hrc graph for one case, supervise it, report at the end.

    ros2 run hrc_bringup session --case 2 --seed 0            # headless, simulated human
    ros2 run hrc_bringup session --case 1 --mode realtime --human auto --subject-id P07

It starts sim, agent, human and recorder as separate processes (the executables ``ros2 run``
starts) with one parameter file composed from ``params/*.yaml`` (see
hrc_common.session_plan), prints a progress line per episode, and stops everything when the
agent finishes, a node dies, or on Ctrl-C / SIGTERM, the recorder last so its bags are closed.
Then it runs the report.

Live sessions (hrc_live, docs/live_study.md): ``--display`` also starts the display node (the
person's page and the experimenter's console on localhost); ``--params FILE`` merges a
parameter file such as the one ``joystick_setup`` writes; the operator pauses, resumes or
aborts with ``ros2 run hrc_live operator ...`` or the console's buttons. An operator abort is a
clean stop: the bags are closed, the runner prints the command that resumes the session from
its last checkpoint (counters continue), and exits with code 3 (EXIT_OPERATOR_ABORT).

The person's time only when needed: in a realtime session the agent runs the training steps
without the person in lockstep (as fast as the graph goes) and switches the sim to realtime
for the episodes with the person (``ResetEpisode.clock_mode``); the runner prints how long the
robot practised alone and when the person joined.

Never a silent stand-in: in realtime with ``--human device``, ``joy`` or ``auto`` the runner
does not start until the input is there (it lists the joystick devices it sees and how to fix
it);
the human node holds zero and asks to pause when its input is lost (``on_input_lost: pause``,
its ``/hrc/human/input`` status) and the runner then pauses the session at once (the agent is
stopped mid-episode: zero commands, the sim holds; the page, the console and ``operator
status`` say "joystick disconnected"); after the human node reports the input back the
operator resumes (``operator resume`` or the console) and the agent continues from the last
finished episode. ``--stand-in sim`` asks for the simulated human instead.

Exit codes: 0 done, 1 a node failed, 2 bad arguments, 3 aborted by the operator, 124 timeout,
130/143 SIGINT/SIGTERM.
"""

import argparse
from dataclasses import replace
import os
import pathlib
import re
import shlex
import signal
import subprocess
import sys
import time

from diagnostic_msgs.msg import DiagnosticStatus
from hrc_common import paths, qos, topics
from hrc_common.contract import ACTIVE_PHASES, DOF_INDEX, Phase, phase_label, source_label
from hrc_common.executables import executable_path
from hrc_common.session_control import (ABORT_SERVICE, EXIT_OPERATOR_ABORT, LATEST_CHECKPOINT,
                                        OPERATOR_SERVICES)
from hrc_common.session_plan import (compose, NODES, new_session_id, parse_overrides,
                                     SessionSettings, write_session_files)
from hrc_live.input_check import (device_missing_message, device_presence, INPUT_LOST_TOPIC,
                                  joy_missing_message, joystick_devices, lost_reason)
from hrc_live.study import (append_index, consent_problem, IndexEntry, load_registry,
                            position_of, StudyError)
from hrc_msgs.msg import EpisodeSummary, HumanAction, SessionStatus, TaskState
from hrc_msgs.srv import ResetEpisode
import rclpy
from rclpy.context import Context
from std_msgs.msg import String
from std_srvs.srv import Trigger
import yaml

from hrc_bringup.supervisor import describe_exit, Supervisor

# Seconds given to DDS discovery after every practice node is seen, before the sim starts.
DISCOVERY_SETTLE_S = 1.0
# issue 25: the largest ROS_DOMAIN_ID: the RTPS port of domain d is 7400 + 250 d + offsets, and
# 232 is the last id whose ports fit in 16 bits (ROS 2 docs, "The ROS_DOMAIN_ID").
MAX_DOMAIN_ID = 232
# issue 25: seconds the runner waits for the display's address in its log before going on.
DISPLAY_ADDRESS_WAIT_S = 15.0
# Seconds the runner keeps serving the operator services after a resume it answered.
SERVICE_RETIRE_S = 1.0
# Link watchdog: a gap between states longer than this (s) is a break or a pause, not a loss;
# the human node's input status comes at least every second, so this long without it (s) means
# its station is unreachable.
STATE_GAP_S = 0.5
STATUS_SILENCE_S = 2.5
# Stop order: the actors first, the recorder last so it records everything and closes its bags.
STOP_ORDER = ('agent', 'human', 'sim', 'recorder')


def parse_args(argv=None):
    """Parse the command line into (SessionSettings, options)."""
    parser = argparse.ArgumentParser(
        prog='session', description='Run one hrc session (one case, one seed): sim, agent, '
        'human and recorder as supervised processes, then the report.')
    parser.add_argument('--case', type=int, default=2, help='paper case 1..6 (default 2)')
    parser.add_argument('--seed', type=int, default=0, help='session seed (default 0)')
    parser.add_argument('--mode', choices=('lockstep', 'realtime'), default='lockstep',
                        help='lockstep: as fast as the graph allows (headless); realtime: '
                        'every 0.2 s of wall time (a person at the joystick)')
    parser.add_argument('--human', dest='human_input', default='sim',
                        choices=('sim', 'auto', 'device', 'joy', 'script'),
                        help='human input (default sim: the simulated human; script: a '
                        'scripted stick in simulation time, --set human.script_file=PATH)')
    parser.add_argument('--profile', dest='human_profile', default='',
                        help='simulated-human profile (params/sim_human.yaml)')
    parser.add_argument('--episodes', dest='training_episodes', type=int, default=0,
                        help='max training episodes (default: params/agent.yaml)')
    parser.add_argument('--eval-episodes', dest='evaluation_episodes', type=int, default=-1,
                        help='evaluation episodes (default: params/agent.yaml)')
    parser.add_argument('--session-id', default='', help='default: case<N>-seed<S>-<time>')
    parser.add_argument('--bags-dir', default='bags', help='bags go to <bags-dir>/<session>')
    parser.add_argument('--runs-dir', default='runs',
                        help='logs, parameters, checkpoints and report go to <runs-dir>')
    parser.add_argument('--params-dir', default=None, help='default: ./params or installed')
    parser.add_argument('--no-record', dest='record', action='store_false',
                        help='do not start the recorder')
    parser.add_argument('--resume-from', default='', help='agent checkpoint to resume')
    parser.add_argument('--subject-id', default='', help='pseudonymous subject id (bag metadata)')
    parser.add_argument('--notes', default='', help='free-text notes (bag metadata)')
    parser.add_argument('--set', dest='overrides', action='append', default=[],
                        metavar='NODE.PARAM=VALUE', help='override a node parameter (repeatable)')
    parser.add_argument('--params', dest='params_files', action='append', default=[],
                        metavar='FILE', help='a ROS 2 parameter file whose node sections '
                        'override params/*.yaml, e.g. the joystick_setup output (repeatable; '
                        '--set wins)')
    parser.add_argument('--display', action='store_true',
                        help='also start the display node (hrc_live): the page for the person '
                        'on http://127.0.0.1:<port>/ and the console on /console '
                        '(params/display.yaml)')
    parser.add_argument('--display-port', type=int, default=None, metavar='PORT',
                        help='port of the pages (default: params/display.yaml; 0 = any free)')
    parser.add_argument('--tlx', action='store_true',
                        help='with --display: ask the raw NASA-TLX on the page when the '
                        'session is done; stored in <runs-dir>/<session>/tlx.yaml (0600)')
    parser.add_argument('--tlx-wait', type=float, default=600.0, metavar='S',
                        help='with --tlx: keep the page up this long for the answer after the '
                        'session (default 600 s)')
    parser.add_argument('--stand-in', choices=('none', 'sim'), default='none',
                        help='realtime with --human device|joy|auto: what drives the human side '
                        'when the input is lost: none (default) = the session pauses until '
                        'the operator resumes; sim = the simulated human (its episodes are '
                        'marked simulated in the bags)')
    parser.add_argument('--practice', type=int, default=0, metavar='N',
                        help='before the condition: N practice episodes of the person alone on '
                        'their degree of freedom (realtime, no robot), recorded as the session '
                        '<session-id>-practice and counted apart (default 0)')
    parser.add_argument('--study-dir', default='',
                        help='the study folder (ros2 run hrc_live study): the subject must be '
                        'registered there with consent yes; the session is added to its '
                        'per-subject index')
    parser.add_argument('--remote', dest='remote_nodes', action='append', default=[],
                        choices=('human',), help='a node that runs on another host and is not '
                        "started here: 'human' = the person's station runs the human node with "
                        "this session's parameters.yaml (docs/two_hosts.md)")
    parser.add_argument('--link-timeout', type=float, default=1.0, metavar='S',
                        help='realtime with a person: states run but no answer from the '
                        "person's side for this long (a network link to the station down, the "
                        'human node stalled) pauses the session as a lost joystick does '
                        '(default 1.0 s = 5 control periods)')
    parser.add_argument('--input-wait', type=float, default=120.0, metavar='S',
                        help='realtime with --human device|joy|auto: wait this long for the input '
                        'before refusing to start (default 120 s)')
    parser.add_argument('--domain-id', type=int, default=None,
                        help='ROS_DOMAIN_ID of the session (default: the environment)')
    parser.add_argument('--no-report', dest='report', action='store_false',
                        help='skip the report at the end')
    parser.add_argument('--recorder-niceness', type=int, default=10, choices=range(0, 20),
                        metavar='0..19', help='run the recorder at this lower CPU priority '
                        '(default 10): it buffers and catches up between episodes, so it does '
                        'not slow the control loop; 0 = same priority as the nodes')
    parser.add_argument('--timeout', type=float, default=0.0,
                        help='stop the session after this many wall seconds (0 = none)')
    options = parser.parse_args(argv)
    options.argv = list(sys.argv[1:] if argv is None else argv)
    overrides = {}
    for path in options.params_files:
        try:
            overrides.update(file_overrides(path))
        except (OSError, ValueError, yaml.YAMLError) as error:
            parser.error(f'--params {path}: {error}')
    try:
        overrides.update(parse_overrides(options.overrides))
    except ValueError as error:
        parser.error(str(error))
    settings = SessionSettings(
        case=options.case, seed=options.seed, mode=options.mode,
        human_input=options.human_input, human_profile=options.human_profile,
        training_episodes=options.training_episodes,
        evaluation_episodes=options.evaluation_episodes, session_id=options.session_id,
        bags_dir=options.bags_dir, runs_dir=options.runs_dir, record=options.record,
        resume_from=options.resume_from, subject_id=options.subject_id, notes=options.notes,
        overrides=overrides)
    if not settings.session_id:
        settings.session_id = new_session_id(settings)
    reasons = settings.check()
    if settings.subject_id and settings.subject_id.lower() in settings.session_id.lower():
        # Bag and run folders are named after the session id: no personal data in file names.
        reasons.append('the session id must not contain the subject id (it names files)')
    if options.tlx and not options.display:
        reasons.append('--tlx needs --display (the questionnaire is on the page)')
    # issue 25: an id outside DDS's range is refused before anything starts
    if options.domain_id is not None and not 0 <= options.domain_id <= MAX_DOMAIN_ID:
        reasons.append(f'--domain-id {options.domain_id} is outside the range of DDS domain '
                       f'ids 0..{MAX_DOMAIN_ID} (higher ids give UDP ports above 65535)')
    if options.input_wait < 0:
        reasons.append('--input-wait must be >= 0')
    if not options.link_timeout > 0:
        reasons.append('--link-timeout must be > 0')
    if options.practice < 0:
        reasons.append('--practice must be >= 0')
    if options.practice and settings.mode != 'realtime':
        reasons.append('--practice needs --mode realtime (the person practises at the '
                       'control rate)')
    if options.study_dir:
        if not settings.subject_id:
            reasons.append('--study-dir needs --subject-id (the registered pseudonym)')
        else:
            try:
                problem = consent_problem(load_registry(options.study_dir),
                                          settings.subject_id)
            except StudyError as error:
                problem = str(error)
            if problem:
                reasons.append(problem)
    if reasons:
        parser.error('; '.join(reasons))
    return settings, options


def person_input(settings: SessionSettings, options) -> str:
    """Return 'device', 'joy' or 'auto' when a person's input must be there, else ''.

    ``auto`` takes the device, else /joy, and never the simulated human (the human node).
    """
    if settings.mode == 'realtime' and settings.human_input in ('device', 'joy', 'auto'):
        return settings.human_input
    return ''


def file_overrides(path) -> dict:
    """Return {'node.name': value} of the node sections of a ROS 2 parameter file."""
    document = yaml.safe_load(pathlib.Path(path).read_text()) or {}
    if not isinstance(document, dict):
        raise ValueError('not a parameter file (a mapping of node sections)')
    overrides = {}
    for node, section in document.items():
        if node not in NODES:
            raise ValueError(f'section {node!r} is not one of the nodes {sorted(NODES)}')
        values = (section or {}).get('ros__parameters') or {}
        overrides.update({f'{node}.{name}': value for name, value in values.items()})
    return overrides


def resume_command(options, session_id: str, checkpoint: pathlib.Path) -> str:
    """Return the command line that resumes this session from ``checkpoint``."""
    args, skip = [], False
    for arg in options.argv:
        if skip:
            skip = False
            continue
        if arg in ('--resume-from', '--session-id'):
            skip = True
            continue
        if arg.startswith(('--resume-from=', '--session-id=')):
            continue
        args.append(arg)
    return shlex.join(['ros2', 'run', 'hrc_bringup', 'session', *args, '--session-id',
                       session_id, '--resume-from', str(checkpoint)])


class Progress:
    """Listens to /hrc/session and /hrc/episode and prints what happens (one rclpy node)."""

    def __init__(self, context, interactive: bool):
        self.node = rclpy.create_node('session_runner', context=context)
        self.interactive = interactive
        self.status = None
        self.episodes = []
        self.started = time.monotonic()
        self.alone_since = None     # (monotonic s, training episodes done) the robot went alone
        self.person_joined = None   # monotonic s the person's first training step was announced
        self.node.create_subscription(SessionStatus, topics.SESSION, self._on_status,
                                      qos.SESSION_QOS)
        self.node.create_subscription(EpisodeSummary, topics.EPISODE, self._on_episode,
                                      qos.EPISODE_QOS)
        self.input_source = None   # (source, detail) of the person's side, as last announced
        self.node.create_subscription(HumanAction, topics.HUMAN_ACTION, self._on_action,
                                      qos.HUMAN_ACTION_QOS)

    def _on_status(self, status):
        # Announce what changes the task for the team; the training <-> updating toggles between
        # episodes are shown on the progress line only.
        def milestone(status):
            phase = phase_label(status.phase, '?')
            return (status.training_step, status.human_involved,
                    phase if phase not in ('training', 'updating') else 'training')

        changed = self.status is None or milestone(status) != milestone(self.status)
        if (changed and status.strategy != 'practice'
                and phase_label(status.phase, '') in ('evaluation', 'done')
                and (self.status is None or phase_label(self.status.phase, '') in (
                    'training', 'updating', 'paused'))):
            self._say_if_not_converged(status)    # issue 25
        self.status = status
        self._track_person_time(status)
        if changed:
            self._print(f'[session] case {status.case_id} {status.strategy}: training step '
                        f'{status.training_step + 1}/{max(status.training_step_count, 1)}, '
                        f'phase {milestone(status)[2]}, human '
                        f'{"involved" if status.human_involved else "not involved"}, robot '
                        f'subtasks {list(status.robot_subtasks)}, human subtasks '
                        f'{list(status.human_subtasks)}', permanent=True)

    def _say_if_not_converged(self, status):
        """Say when training ended without the robot converging (issue 25), with the numbers."""
        training = [summary for summary in self.episodes if not summary.evaluation]
        if training and training[-1].converged:
            return
        cap = getattr(self, 'max_training_episodes', None)
        current = training[-1].training_step if training else status.training_step
        step = f'training step {current + 1} of {max(status.training_step_count, 1)}'
        never = ('; the person never trained with the robot' if status.human_subtasks
                 and self.person_joined is None else '')
        self._print(f'[session] the robot did not converge in {status.total_episodes} '
                    f'episodes ({step}' + (f', at most {cap}' if cap else '') + ')' + never
                    + ('; the test episodes start' if phase_label(status.phase, '')
                       == 'evaluation' else ''), permanent=True)

    def _on_action(self, action):
        """Say which input drives the person's side whenever it changes (never silently)."""
        if action.source_detail.startswith('not involved'):
            return  # zero on purpose: the person has no part in this training step
        source = source_label(action.source)
        detail = action.source_detail.split(' (', 1)[0] if source != 'none' \
            else action.source_detail
        if (source, detail) != self.input_source:
            self.input_source = (source, detail)
            self._print(f'[session] the human side is driven by: {source} ({detail})',
                        permanent=True)

    def restart(self) -> None:
        """Forget the practice: the condition's clock and person time start now."""
        self.status, self.episodes = None, []
        self.started = time.monotonic()
        self.alone_since = self.person_joined = None

    def _track_person_time(self, status):
        """Note when the robot practises alone and when the person joins; say so once."""
        now = time.monotonic()
        if status.strategy == 'practice':
            return
        if not status.human_involved and phase_label(status.phase, '') in ('training',
                                                                            'updating'):
            if self.alone_since is None:
                self.alone_since = (now, status.total_episodes)   # (when, episodes then)
            return
        if status.human_involved and self.person_joined is None and status.phase in (
                Phase.TRAINING, Phase.UPDATING):
            self.person_joined = now
            alone = ''
            lonely = status.total_episodes - status.human_involved_episodes
            if self.alone_since is not None:
                # Counted from this one status, not from the first lonely one this runner saw:
                # a busy runner may miss statuses (the agent keeps only the newest), and every
                # episode so far without the person was the robot's own.
                alone = (f'; the robot practised alone: {lonely} episodes '
                         f'in {now - self.alone_since[0]:.0f} s')
            elif lonely > 0:
                # This runner's session reader matched the agent only after the robot's lonely
                # episodes (a short lockstep phase on a busy machine): their time is bounded by
                # the session's so far.
                alone = (f'; the robot practised alone: {lonely} episodes '
                         f'in at most {now - self.started:.0f} s')
            self._print(f'[session] the person joins now, at episode '
                        f'{status.total_episodes + 1}, {now - self.started:.0f} s after the '
                        f'start{alone}', permanent=True)

    def _on_episode(self, summary):
        if any(seen.episode == summary.episode for seen in self.episodes):
            return
        self.episodes.append(summary)
        # Training and test episodes with the person, as the page counts them.
        human_episodes = sum(s.human_involved for s in self.episodes)
        steps = max(self.status.training_step_count, 1) if self.status else 1
        case = self.status.case_id if self.status else summary.case_id
        self._print(f'[case {case} | step {summary.training_step + 1}/{steps} | episode '
                    f'{summary.episode:3d} | {"evaluation" if summary.evaluation else "training"}'
                    f'] return {summary.episode_return:7.1f}  error slider '
                    f'{summary.slider_error:.3f} m  pendulum {summary.pendulum_error:.3f} rad  '
                    f'ball {summary.ball_error:.3f} m  human '
                    f'{"yes" if summary.human_involved else "no "} ({human_episodes} so far)'
                    + ('  converged' if summary.converged else ''),
                    permanent=not self.interactive or summary.evaluation or summary.converged)

    def _print(self, line, permanent=True):
        """Print a line; on a terminal, a non-permanent line is overwritten by the next one."""
        if self.interactive:
            print('\r\033[K' + line, end='\n' if permanent else '', flush=True)
        else:
            print(line, flush=True)

    def close(self):
        """Destroy the node."""
        self.node.destroy_node()


class InputGuard:
    """Pauses the session at once when the person's input is lost; resumes on the operator's word.

    Watches ``/hrc/human/action``: an answer holding zero because the input is lost
    (:func:`hrc_live.input_check.lost_reason`) while the person is involved makes the runner
    stop the agent mid-episode (its abort service: zero commands, the sim holds, the last
    checkpoint kept), say "joystick disconnected" on ``/hrc/session/input_lost`` (the pages) and
    on ``/hrc/session`` (phase paused, for ``operator status``), and serve the operator services
    itself until the operator resumes after the input is back; then the agent is started again
    from the last finished episode.
    """

    def __init__(self, node, kind: str, device: str, link_timeout: float = 1.0):
        self.node, self.kind, self.device = node, kind, device
        self.lost = ''                  # why the input is lost ('' = it is not)
        # The link watchdog (two hosts, docs/two_hosts.md): monotonic s of the newest state,
        # of the newest answer from the person's side and of the human node's newest status.
        self.link_timeout = link_timeout
        self.last_state_at = self.last_action_at = self.input_status_at = None
        self.states_flow_since = None   # states run again after a gap (break, pause) since
        self.involved = False           # the person acts in the current training step
        self.agent_down = False         # the agent was stopped for the loss and has exited
        self.resume_requested = False
        self.abort_requested = False
        self.last_status = None
        self._services = []
        self._practice_told = False
        self._retire_at = 0.0
        self._status_pub = None
        self._string = String
        self._trigger = Trigger
        self._session_status = SessionStatus
        self._topics, self._qos = topics, qos
        self.lost_pub = node.create_publisher(String, INPUT_LOST_TOPIC, qos.SESSION_QOS)
        self.lost_pub.publish(String(data=''))
        self.abort_client = node.create_client(Trigger, ABORT_SERVICE)
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
        if self.kind == 'joy' or publishers:
            return publishers > 0, joy_missing_message(publishers)
        return False, (device_missing_message(self.device, why, joystick_devices()) + ' Or: '
                       + joy_missing_message(publishers))

    def _on_status(self, status):
        if self._status_pub is None:   # the agent's, not our own stand-in status
            self.last_status = status
            self.involved = bool(status.human_involved)
            # The person's step begins while their input is already gone: pause now.
            if self.involved and self.input_status.get('pause_requested') == 'true':
                self._lose(self.input_status.get('message') or 'the human node asks to pause')

    def _on_input_status(self, status):
        values = {item.key: item.value for item in status.values}
        values['message'] = status.message
        self.input_status = values
        self.input_status_at = time.monotonic()
        if values.get('pause_requested') == 'true' and self.involved:
            self._lose(status.message or 'the human node asks to pause')

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
            if not self._practice_told:  # no agent to stop: say it, the human node holds 0
                self._practice_told = True
                print(f'[session] practice: {reason}; the human node holds zero, the practice '
                      f'goes on', flush=True)
            return
        if not reason.startswith('joystick disconnected'):
            reason = f'joystick disconnected: {reason}'
        self.lost = reason
        print(f'[session] {reason}: pausing the session now (the agent stops mid-episode, '
              f'the sim holds, zero commands); resume with "ros2 run hrc_live operator '
              f'resume" or the console once it is back', flush=True)
        self.lost_pub.publish(self._string(data=reason))
        if self.abort_client.service_is_ready():
            self.abort_client.call_async(self._trigger.Request())

    def on_agent_exit(self) -> None:
        """Stand in for the agent stopped for the loss: operator services, phase paused."""
        self.agent_down = True
        if self._services:  # lost again before the last stand-in services were retired
            return self._publish_paused()
        self._services = [self.node.create_service(self._trigger, OPERATOR_SERVICES[name],
                                                    getattr(self, f'_serve_{name}'))
                          for name in ('pause', 'resume', 'abort')]
        self._publish_paused()

    def _publish_paused(self) -> None:
        """Say on /hrc/session (for ``operator status``) that the session is paused, and why."""
        self._status_pub = self.node.create_publisher(self._session_status,
                                                      self._topics.SESSION,
                                                      self._qos.SESSION_QOS)
        if self.last_status is not None:
            status = self.last_status
            status.phase = int(Phase.PAUSED)
            status.message = f'{self.lost}: paused; resume after it is back'

            self._status_pub.publish(status)

    def _serve_pause(self, request, response):
        response.success, response.message = True, f'already paused: joystick disconnected ' \
            f'({self.lost})'
        return response

    def _serve_resume(self, request, response):
        present, why = self.present()
        if not present:
            response.success = False
            response.message = f'the joystick is still disconnected: {why}'
            return response
        self.resume_requested = True
        response.success = True
        response.message = ('resuming: the agent continues from the last finished episode '
                            '(the interrupted one runs again)')
        return response

    def _serve_abort(self, request, response):
        self.abort_requested = True
        response.success, response.message = True, 'aborted while paused (joystick ' \
            'disconnected); resume from the last checkpoint'
        return response

    def resumed(self) -> None:
        """Stop standing in for the agent (it is starting again)."""
        if self._status_pub is not None:
            self.node.destroy_publisher(self._status_pub)
            self._status_pub = None
        # The services go a moment later: the answer to the resume call must reach the caller
        # first (the new agent takes seconds to serve them itself).
        self._retire_at = time.monotonic() + SERVICE_RETIRE_S
        self.lost, self.agent_down, self.resume_requested = '', False, False
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
        """Retire the stand-in operator services once their last answer is out."""
        self.watch_link()
        if self._services and not self.agent_down and time.monotonic() > self._retire_at:
            for service in self._services:
                self.node.destroy_service(service)
            self._services = []


def wait_for_input(guard: InputGuard, executor, timeout: float, stop_reason: list) -> bool:
    """Wait until the person's input is there; say what is missing and how to fix it."""
    deadline = time.monotonic() + timeout
    said = ''
    while True:
        present, why = guard.present()
        if present:
            if said:
                print(f'[session] the input is there now: {why}', flush=True)
            return True
        if why != said:
            print(f"[session] waiting for the person's input (up to {timeout:.0f} s): {why}",
                  flush=True)
            said = why
        if time.monotonic() > deadline or stop_reason:
            print(f'[session] not started: {why}', file=sys.stderr, flush=True)
            return False
        executor.spin_once(timeout_sec=0.2)


def write_parameters(parameters: dict, path: pathlib.Path) -> pathlib.Path:
    """Write a ROS 2 parameter file with a section per node."""
    path.write_text(yaml.safe_dump(
        {node: {'ros__parameters': values} for node, values in parameters.items()},
        sort_keys=False))
    return path


def run_session(settings: SessionSettings, options) -> int:
    """Run one session; return the exit code (0 = the agent finished the session)."""
    params_dir = pathlib.Path(options.params_dir) if options.params_dir else paths.params_dir()
    try:
        parameters = compose(settings, params_dir)
    except (ValueError, OSError) as error:
        print(f'session: {error}', file=sys.stderr)
        return 2
    run_dir = pathlib.Path(settings.runs_dir) / settings.session_id
    if settings.subject_id:
        # issue 25: with a subject id everything the session writes is owner-only (files
        # 0600, folders 0700): the nodes inherit the mask (checkpoints, run and bag folders)
        os.umask(0o077)
    if settings.record:
        parameters['recorder']['session_config'] = str(run_dir / 'session.yaml')
    live_input = person_input(settings, options)
    if live_input:
        # Never a silent stand-in: the simulated human only when the operator asked for it.
        parameters['human']['on_input_lost'] = 'sim' if options.stand_in == 'sim' else 'pause'
    if 'human' in options.remote_nodes:
        # The station's human node is started by hand, possibly long after this runner: the
        # agent waits for it (wait_for_subscribers) as long as the runner waits for its input.
        agent = parameters['agent']
        agent['reset_timeout'] = max(float(agent['reset_timeout']), float(options.input_wait))
    params_path, _ = write_session_files(settings, parameters, run_dir)

    env = dict(os.environ)
    if options.domain_id is not None:
        env['ROS_DOMAIN_ID'] = str(options.domain_id)
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    # A resumed session keeps the logs of the run it continues.
    logs = 'logs' if not settings.resume_from else time.strftime('logs-resumed-%Y%m%d-%H%M%S')
    supervisor = Supervisor(run_dir / logs, env)
    print(f'[session] {settings.session_id}: case {settings.case}, seed {settings.seed}, '
          f'{settings.mode}, human input {settings.human_input}; logs and parameters in '
          f'{run_dir}' + (f', bags in {pathlib.Path(settings.bags_dir) / settings.session_id}'
                          if settings.record else ''), flush=True)

    stop_reason = []

    def on_signal(signum, frame):
        stop_reason.append(signal.Signals(signum).name)

    previous = {sig: signal.signal(sig, on_signal) for sig in (signal.SIGINT, signal.SIGTERM)}
    context = Context()
    rclpy.init(context=context, domain_id=options.domain_id,
               signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    progress = Progress(context, sys.stdout.isatty())
    progress.max_training_episodes = parameters['agent'].get('max_training_episodes')  # issue 25
    executor = rclpy.executors.SingleThreadedExecutor(context=context)
    executor.add_node(progress.node)
    guard = (InputGuard(progress.node, live_input, parameters['human'].get('device', ''),
                        options.link_timeout)
             if live_input and options.stand_in == 'none' else None)
    code = 0
    start = time.monotonic()
    started = time.strftime('%Y-%m-%dT%H:%M:%S')
    restarts = 0
    try:
        if options.display:
            # issue 25: served from the start (the waiting-for-the-joystick screen included)
            supervisor.start('display', display_command(options, params_dir, run_dir))
            print_display_address(supervisor.processes['display'], executor, stop_reason)
        if live_input and not wait_for_input(
                guard or InputGuard(progress.node, live_input,
                                    parameters['human'].get('device', '')),
                executor, options.input_wait, stop_reason):
            return 2
        if options.practice:
            practice_started = time.strftime('%Y-%m-%dT%H:%M:%S')
            practice_code = run_practice(settings, options, params_dir, env, progress,
                                         executor, stop_reason)
            index_session(settings, options, 'practice', practice_started, practice_code)
            if practice_code != 0:
                return practice_code
            progress.restart()
            started = time.strftime('%Y-%m-%dT%H:%M:%S')
            if guard is not None:
                guard.resumed()  # nothing to resume: an input lost in practice is only told
        # The recorder first, so it sees the first state; the sim before the agent resets it.
        for node in ('recorder', 'sim', 'human', 'agent'):
            if node not in parameters or node in options.remote_nodes:
                continue
            package, executable, _ = NODES[node]
            supervisor.start(node, [str(executable_path(package, executable)), '--ros-args',
                                    '--params-file', str(params_path)],
                             niceness=options.recorder_niceness if node == 'recorder' else 0)
        while True:
            executor.spin_once(timeout_sec=0.1)
            if stop_reason:
                print(f'[session] {stop_reason[0]} received: stopping the session', flush=True)
                code = 130 if stop_reason[0] == 'SIGINT' else 143
                break
            if guard is not None:
                guard.tick()
            if guard is not None and guard.agent_down:
                if guard.abort_requested:
                    print('[session] the operator aborted the session while it was paused '
                          '(joystick disconnected)', flush=True)
                    code = EXIT_OPERATOR_ABORT
                    break
                if guard.resume_requested:
                    restarts += 1
                    restart_agent(supervisor, parameters, settings, run_dir, restarts)
                    guard.resumed()
                    print('[session] resumed by the operator: the agent continues from the '
                          'last finished episode', flush=True)
                    continue
            finished = supervisor.exited()
            if finished:
                first = finished[0]
                if (guard is not None and guard.lost and first.name == 'agent'
                        and first.returncode == EXIT_OPERATOR_ABORT and not guard.agent_down):
                    guard.on_agent_exit()
                    print('[session] paused (joystick disconnected): waiting for the input and '
                          "the operator's resume", flush=True)
                    continue
                if guard is not None and guard.agent_down and first.name == 'agent':
                    finished = finished[1:]
                    if not finished:
                        continue
                    first = finished[0]
                if first.name == 'agent' and first.returncode == 0:
                    print('[session] the agent finished the session', flush=True)
                    if options.tlx:
                        wait_for_tlx(run_dir / 'tlx.yaml', settings.session_id, executor,
                                     options.tlx_wait, stop_reason)
                elif first.name == 'agent' and first.returncode == EXIT_OPERATOR_ABORT:
                    message = progress.status.message if progress.status else ''
                    print(f'[session] the operator aborted the session ({message}); stopping '
                          f'the other nodes and closing the bags', flush=True)
                    code = EXIT_OPERATOR_ABORT
                else:
                    print(f'[session] node {first.name} stopped unexpectedly '
                          f'({describe_exit(first.returncode)}); stopping the session. Last '
                          f'output of {first.name}:\n{first.tail()}', file=sys.stderr, flush=True)
                    code = 1
                break
            if options.timeout and time.monotonic() - start > options.timeout:
                print(f'[session] timeout of {options.timeout:.0f} s reached: stopping',
                      file=sys.stderr, flush=True)
                code = 124
                break
    finally:
        exits = supervisor.stop_all(STOP_ORDER)
        # Let the last episode summaries arrive before closing.
        progress.close()
        executor.shutdown()
        rclpy.shutdown(context=context)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    elapsed = time.monotonic() - start
    print(f'[session] stopped after {elapsed:.1f} s: ' + ', '.join(
        f'{name} {describe_exit(returncode)}' for name, returncode in exits.items()), flush=True)
    if exits.get('recorder', 0) not in (0, None) and code in (0, EXIT_OPERATOR_ABORT):
        print('[session] the recorder did not exit cleanly: check its log', file=sys.stderr)
        code = 1
    if code == EXIT_OPERATOR_ABORT:
        checkpoint = (pathlib.Path(parameters['agent']['checkpoint_dir']) / settings.session_id
                      / LATEST_CHECKPOINT)
        if checkpoint.is_file():
            print(f'[session] to resume from the last finished episode (counters continue):\n'
                  f'  {resume_command(options, settings.session_id, checkpoint)}', flush=True)
        else:
            print('[session] no episode had finished: there is no checkpoint to resume from',
                  flush=True)
    if settings.record and options.report and (code == 0 or progress.episodes):
        report(settings, run_dir)
    index_session(settings, options, 'condition', started, code)
    if settings.subject_id:
        owner_only(settings, parameters)    # issue 25
    return code


def owner_only(settings: SessionSettings, parameters: dict) -> None:
    """Make every output of a session with a subject id owner-only (issue 25).

    The umask set at the start makes new files 0600 and folders 0700; a few writers set their
    mode themselves (hrc_common.contract.atomic_write: 0644 by default, e.g. the checkpoints),
    so the session's folders (run, bags, checkpoints; the practice's too) are gone over once
    more at the end: files 0600, folders 0700.
    """
    roots = []
    for session_id in (settings.session_id, settings.session_id + '-practice'):
        roots += [pathlib.Path(settings.runs_dir) / session_id,
                  pathlib.Path(settings.bags_dir) / session_id,
                  pathlib.Path(parameters['agent']['checkpoint_dir']) / session_id]
    for root in roots:
        if not root.is_dir() or root.is_symlink():
            continue
        for path in [root, *root.rglob('*')]:
            if path.is_symlink():
                continue
            try:
                path.chmod(0o700 if path.is_dir() else 0o600)
            except OSError as error:
                print(f'[session] could not make {path} owner-only: {error}', file=sys.stderr)


def index_session(settings: SessionSettings, options, kind: str, started: str,
                  code: int) -> None:
    """Add the session to the study's per-subject index (with --study-dir)."""
    if not options.study_dir:
        return
    session_id = settings.session_id + ('-practice' if kind == 'practice' else '')
    run_dir = pathlib.Path(settings.runs_dir) / session_id
    tlx = run_dir.parent / settings.session_id / 'tlx.yaml'
    entry = IndexEntry(
        subject_id=settings.subject_id, session_id=session_id, case=settings.case, kind=kind,
        position=position_of(load_registry(options.study_dir), settings.subject_id,
                             settings.case),
        started=started, ended=time.strftime('%Y-%m-%dT%H:%M:%S'), exit_code=int(code),
        bags=str((pathlib.Path(settings.bags_dir) / session_id).resolve()),
        run_dir=str(run_dir.resolve()),
        tlx_file=str(tlx.resolve()) if options.tlx and kind == 'condition' else '')
    path = append_index(options.study_dir, entry)
    print(f'[session] {kind} {session_id} added to the study index {path}', flush=True)


def practice_subtask(human_dof: str) -> str:
    """Return the subtask the person holds alone on their degree of freedom."""
    return 'slider' if human_dof == 'translation' else 'pendulum'


def wait_for_closed_episode(recorder, episode: int, executor, stop_reason: list,
                            timeout: float = 30.0) -> bool:
    """Wait until the recorder closed the file of ``episode`` (its log says so).

    Without an agent no EpisodeSummary closes it: the recorder closes it ``summary_timeout``
    after its final state, later when it lags behind; stopping it earlier would lose the
    messages still queued.
    """
    deadline = time.monotonic() + timeout
    mark = f'episode {episode}: closed'
    while time.monotonic() < deadline and not stop_reason:
        if mark in recorder.tail(lines=50) or recorder.returncode is not None:
            return True
        executor.spin_once(timeout_sec=0.2)
    return False


def run_practice(settings: SessionSettings, options, params_dir: pathlib.Path, env: dict,
                 progress: 'Progress', executor, stop_reason: list) -> int:
    """Run the practice: the person alone on their degree of freedom, realtime, no robot.

    The sim (waiting for no robot), the human node and the recorder run as in the condition;
    the runner starts each of the ``options.practice`` episodes itself (``/hrc/sim/reset``,
    realtime clock) once everything listens, with the agent's ``episode_break`` between them,
    and announces the practice on /hrc/session (strategy ``practice``) so the human node, the
    page and the recorder know the roles. Recorded as the session ``<session-id>-practice``.
    Returns the exit code (0 = every practice episode ran).
    """
    practice = replace(settings, session_id=f'{settings.session_id}-practice', resume_from='')
    parameters = compose(practice, params_dir)
    episode_break = float(parameters.pop('agent').get('episode_break', 3.0))
    parameters['sim'].update(start_on_launch=False, auto_reset=False, max_episodes=0,
                             expected_actors=['human'])
    if person_input(settings, options):
        parameters['human']['on_input_lost'] = ('sim' if options.stand_in == 'sim'
                                                else 'pause')
    run_dir = pathlib.Path(settings.runs_dir) / practice.session_id
    if settings.record:
        parameters['recorder']['session_config'] = str(run_dir / 'session.yaml')
    params_path, _ = write_session_files(practice, parameters, run_dir)
    supervisor = Supervisor(run_dir / 'logs', env)
    human_dof = parameters['human']['dof']
    robot_dof = parameters['sim']['robot_dof']
    node = progress.node
    publisher = node.create_publisher(SessionStatus, topics.SESSION, qos.SESSION_QOS)
    reset = node.create_client(ResetEpisode, topics.RESET_SERVICE)
    finished = []

    def announce(done: int) -> None:
        publisher.publish(SessionStatus(
            session_id=practice.session_id, case_id=settings.case, strategy='practice',
            training_step=0, training_step_count=1, robot_dof=DOF_INDEX[robot_dof],
            human_dof=DOF_INDEX[human_dof], human_involved=True,
            human_subtasks=[practice_subtask(human_dof)], episode=done, total_episodes=done,
            human_involved_episodes=done, phase=int(Phase.TRAINING),
            message=f'practice: episode {min(done + 1, options.practice)} of '
                    f'{options.practice}, the person alone (the robot does not act)'))

    def on_state(state) -> None:
        if (state.truncated or state.terminated) and state.episode not in finished:
            finished.append(state.episode)
            announce(len(finished))

    def spin_until(condition, seconds: float) -> bool:
        deadline = time.monotonic() + seconds
        while not condition():
            if stop_reason or supervisor.exited() or time.monotonic() > deadline:
                return False
            executor.spin_once(timeout_sec=0.1)
        return True

    subscription = node.create_subscription(TaskState, topics.STATE, on_state, qos.STATE_QOS)
    announce(0)
    print(f'[session] practice: {options.practice} episodes of the person alone on the '
          f'{human_dof} (realtime, the robot does not act), recorded as {practice.session_id}',
          flush=True)
    code = 0
    try:
        for name in ('recorder', 'human', 'sim'):
            if name in parameters:
                package, executable, _ = NODES[name]
                supervisor.start(name, [str(executable_path(package, executable)),
                                        '--ros-args', '--params-file', str(params_path)])
        # The first episode starts once everything listens (the runner, the recorder, the
        # human node, the page on the states; the runner, the recorder, the page on the human's
        # answers) and discovery had a moment to match them all.
        pages = 1 if options.display else 0
        ready = spin_until(lambda: (
            reset.service_is_ready() and node.count_publishers(topics.STATE) >= 1
            and node.count_subscribers(topics.STATE) >= 3 + pages
            and node.count_publishers(topics.HUMAN_ACTION) >= 1
            and node.count_subscribers(topics.HUMAN_ACTION) >= 2 + pages), 60.0)
        spin_until(lambda: False, DISCOVERY_SETTLE_S)
        for episode in range(options.practice if ready else 0):
            if episode:
                spin_until(lambda: False, episode_break)  # the person rests
            reset.call_async(ResetEpisode.Request(seed=-1, episode=episode,
                                                  clock_mode='realtime'))
            if not spin_until(lambda: len(finished) > episode,
                              parameters['sim']['episode_duration'] * 3 + 30.0):
                break
        if len(finished) == options.practice and 'recorder' in supervisor.processes:
            wait_for_closed_episode(supervisor.processes['recorder'], options.practice - 1,
                                    executor, stop_reason)
        if stop_reason:
            code = 130 if stop_reason[0] == 'SIGINT' else 143
        elif len(finished) < options.practice:
            exited = supervisor.exited()
            culprit = exited[0] if exited else None
            print('[session] practice: ' + (
                f'node {culprit.name} stopped unexpectedly ({describe_exit(culprit.returncode)})'
                f':\n{culprit.tail()}' if culprit else
                'the practice episodes did not run (see the logs in ' + str(run_dir) + ')'),
                file=sys.stderr, flush=True)
            code = 1
    finally:
        supervisor.stop_all(('human', 'sim', 'recorder'))
        node.destroy_subscription(subscription)
        node.destroy_publisher(publisher)
        node.destroy_client(reset)
    print(f'[session] practice done: {len(finished)} of {options.practice} episodes'
          if code == 0 else f'[session] practice stopped ({describe_exit(code)})', flush=True)
    return code


def wait_for_tlx(path: pathlib.Path, session_id: str, executor, timeout: float,
                 stop_reason: list) -> bool:
    """Keep the page up until the person sent the NASA-TLX of this session (or timeout)."""
    print(f'[session] waiting up to {timeout:.0f} s for the NASA-TLX on the page (Ctrl-C '
          f'skips it)', flush=True)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not stop_reason:
        try:
            answers = yaml.safe_load(path.read_text()) or []
        except (OSError, yaml.YAMLError):
            answers = []
        if any(isinstance(answer, dict) and answer.get('session_id') == session_id
               for answer in answers):
            print(f'[session] NASA-TLX stored in {path}', flush=True)
            return True
        executor.spin_once(timeout_sec=0.2)
    stop_reason.clear()  # Ctrl-C here only skips the questionnaire
    print('[session] no NASA-TLX answer: the session ends without it', flush=True)
    return False


def print_display_address(display, executor, stop_reason: list) -> None:
    """Print the addresses of the person's page and the console once the display serves.

    (issue 25) Read from the display's log line; its port may be chosen by the system (0).
    """
    deadline = time.monotonic() + DISPLAY_ADDRESS_WAIT_S
    while time.monotonic() < deadline and not stop_reason:
        found = re.search(r'serving the display on (http://\S+?/) ', display.tail(lines=50))
        if found:
            print(f"[session] the person's page: {found.group(1)}   the experimenter's "
                  f'console: {found.group(1)}console', flush=True)
            return
        if display.returncode is not None:
            break
        executor.spin_once(timeout_sec=0.1)
    print(f'[session] the display did not say its address within {DISPLAY_ADDRESS_WAIT_S:.0f} '
          f's: see {display.log_path}', file=sys.stderr, flush=True)


def display_command(options, params_dir: pathlib.Path, run_dir: pathlib.Path) -> list:
    """Return the command line of the display node of this session."""
    command = [str(executable_path('hrc_live', 'display_node')), '--ros-args']
    display_params = params_dir / 'display.yaml'
    if display_params.is_file():
        command += ['--params-file', str(display_params)]
    if options.display_port is not None:
        command += ['-p', f'port:={options.display_port}']
    if options.tlx:
        command += ['-p', f'tlx_file:={(run_dir / "tlx.yaml").resolve()}']
    return command


def restart_agent(supervisor: Supervisor, parameters: dict, settings: SessionSettings,
                  run_dir: pathlib.Path, restarts: int) -> None:
    """Start the agent again from the session's last checkpoint (after a paused input loss)."""
    checkpoint = (pathlib.Path(parameters['agent']['checkpoint_dir']) / settings.session_id
                  / LATEST_CHECKPOINT)
    resumed = {node: dict(values) for node, values in parameters.items()}
    if checkpoint.is_file():
        resumed['agent']['resume_from'] = str(checkpoint)
    path = write_parameters(resumed, run_dir / f'parameters-resume-{restarts}.yaml')
    old_log = supervisor.log_dir / 'agent.log'
    if old_log.is_file():
        old_log.rename(supervisor.log_dir / f'agent-before-resume-{restarts}.log')
    package, executable, _ = NODES['agent']
    supervisor.start('agent', [str(executable_path(package, executable)), '--ros-args',
                               '--params-file', str(path)])


def report(settings: SessionSettings, run_dir: pathlib.Path) -> None:
    """Run the report CLI on the session's bags and print its Table II."""
    bag_dir = pathlib.Path(settings.bags_dir) / settings.session_id
    out_dir = run_dir / 'report'
    result = subprocess.run([str(executable_path('hrc_bag', 'hrc_report')), str(bag_dir),
                             '--out', str(out_dir)], capture_output=True, text=True)
    print(result.stdout, end='')
    for line in result.stderr.splitlines():     # the report's notices and reasons
        print(f'[session] {line}', file=sys.stderr, flush=True)
    if result.returncode != 0:
        print(f'[session] report failed ({describe_exit(result.returncode)})', file=sys.stderr)
        return
    print(f'[session] bags: {bag_dir}   report and figures: {out_dir}', flush=True)


def main(argv=None) -> int:
    """Entry point of ``ros2 run hrc_bringup session``."""
    settings, options = parse_args(argv)
    return run_session(settings, options)


if __name__ == '__main__':
    sys.exit(main())
