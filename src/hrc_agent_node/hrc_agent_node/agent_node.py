"""The agent node (``agent``): the learning robot of a session, driving the episode loop.

Thin: messages in and out, the reset service client, timers and parameters. Everything the
robot decides lives in :class:`hrc_agent_node.agent_core.AgentCore` (shared with the engine).
The step protocol is docs/architecture.md's ("The step protocol"); what the agent observes
of the human and when it updates is in src/hrc_agent_node/README.md. In short: publish
``/hrc/session`` (transient local), call ``/hrc/sim/reset`` (its response carries what the sim
owns: control period, ``max_force``, ``max_torque``), answer every non-final ``/hrc/state``
on ``/hrc/robot/cmd_wrench`` with the state's stamp, publish step k's record
(``/hrc/agent/step``) when state k+1 arrives; on the final state ``/hrc/episode``, the update
when one is due (phase ``updating`` first), a checkpoint, ``/hrc/session``, then the next
reset (in realtime ``episode_break`` wall seconds later). After training the frozen policy is
evaluated; then phase ``done`` and exit 0. The learner's health goes to ``/diagnostics``
(``agent: learner``, :mod:`hrc_agent_node.agent_health`).

Practice (``practice_episodes`` N > 0, the session runner's ``--practice N``): instead of a
session, N episodes of the person alone (``agent_practice``); the agent is the one publisher
of ``/hrc/session`` in practice too.

Operator controls (``/hrc/agent/pause``, ``resume``, ``abort``): ``agent_services``; the
practice's episodes: ``agent_practice``.
"""

import math
import os
import time

from geometry_msgs.msg import WrenchStamped
from hrc_agent_node.agent_core import AgentCore, PopulationStepRefused
from hrc_agent_node.agent_messages import (agent_step_fields, episode_summary_fields,
                                          session_status_fields)
from hrc_agent_node.agent_health import LearnerHealth, update_line
from hrc_agent_node.agent_input_hold import InputHold
from hrc_agent_node.agent_practice import PracticeEpisodes
from hrc_agent_node.agent_startup import SESSION_MATCH_GRACE_S, StartupWait
from hrc_agent_node.agent_services import (ANNOUNCE_ACK_TIMEOUT_S, EXIT_LINGER_S,
                                          OperatorServices)
from hrc_agent_node.checkpoint import (CheckpointError, load_session_start,
                                       remove_stale_temporaries, save_checkpoint)
from hrc_agent_node.config import AgentParams
from hrc_agent_node.practice import PracticeRun
from hrc_agent_node.strategies import CasesError
from hrc_agent_node.task_tree import TaskTreeError
from hrc_common import qos, topics
from hrc_common.contract import os_error_text, Phase, SimLimits
from hrc_common.diagnostics import DiagnosticsReporter
from hrc_common.dof import set_wrench_value
from hrc_common.episode_numbers import episode_number
from hrc_common.nodes import run_node
from hrc_common.params import declare_parameters, ParameterError
from hrc_common.session_control import (ABORT_SERVICE, FINAL_CHECKPOINT,
                                        LATEST_CHECKPOINT, PAUSE_SERVICE, RESUME_SERVICE,
                                        STOP_FOR_INPUT_SERVICE)
from hrc_msgs.msg import AgentStep, EpisodeSummary, HumanAction, SessionStatus, TaskState
from hrc_msgs.srv import ResetEpisode
from rclpy.duration import Duration
from rclpy.node import Node
from std_srvs.srv import Trigger

# Human actions kept for stamp matching (a few steps are enough: they answer the newest state).
HUMAN_ACTIONS_KEPT = 50
TICK_S = 0.02

SUMMARY = ('The learning robot of an hrc session: answers every state on /hrc/robot/cmd_wrench, '
           "learns between episodes, moves through the case's training steps, evaluates, "
           'publishes /hrc/session, /hrc/episode and /hrc/agent/step, and exits 0 when done.')


def stamp_key(stamp) -> tuple:
    """Return a hashable key of a builtin_interfaces/Time."""
    return (int(stamp.sec), int(stamp.nanosec))


class AgentNode(OperatorServices, InputHold, PracticeEpisodes, StartupWait, Node):
    """ROS front of an AgentCore session (see the module docstring for the protocol)."""

    def __init__(self):
        super().__init__('agent')
        self.params = declare_parameters(self, AgentParams)
        try:
            self.core = AgentCore(self.params)
        except (TaskTreeError, CasesError, ValueError) as error:
            raise ParameterError(f'AgentParams rejected: {error}') from None
        self.practice = None            # a PracticeRun when this node runs the practice
        if self.params.practice_episodes:
            if self.params.resume_from:
                raise ParameterError('practice_episodes runs a practice, resume_from a session: '
                                     'give one of them')
            self.practice = PracticeRun(self.params.practice_episodes, self.core.session_id,
                                        self.core.case_id, self.core.robot_dof,
                                        self.core.human_dof, self.core.tree.error)
        try:
            started = load_session_start(self.core)
        except CheckpointError as error:
            raise ParameterError(str(error)) from None
        if started:
            self.get_logger().info(started)
        problem = self.core.population_step_problem() if self.practice is None else ''
        if problem:   # partners first without its pre-training: refused, not a traceback
            raise ParameterError(problem)
        self._create_interfaces()
        self._init_state()
        self.publish_session('session starting: ' + self.core.status_line())
        self.get_logger().info(f'session {self.core.session_id}: {self.core.status_line()}; '
                               f'waiting for {topics.RESET_SERVICE}')
        self.create_timer(TICK_S, self.tick)

    def _create_interfaces(self):
        """Create the publishers, subscriptions, the reset client and the operator services."""
        quiet_pub, quiet_sub = qos.NO_PUBLISHER_EVENTS, qos.NO_SUBSCRIPTION_EVENTS  # wait set
        self.session_pub = self.create_publisher(SessionStatus, topics.SESSION, qos.SESSION_QOS,
                                                 event_callbacks=quiet_pub)
        self.episode_pub = self.create_publisher(EpisodeSummary, topics.EPISODE,
                                                 qos.EPISODE_QOS, event_callbacks=quiet_pub)
        self.step_pub = self.create_publisher(AgentStep, topics.AGENT_STEP,
                                              qos.stream_qos(qos.AGENT_STEP_QOS),
                                              event_callbacks=quiet_pub)
        self.wrench_pub = self.create_publisher(WrenchStamped, topics.ROBOT_CMD_WRENCH,
                                                qos.stream_qos(qos.COMMAND_QOS),
                                                event_callbacks=quiet_pub)
        # every state, also after a stall: each carries the sim's flags of missing commands
        self.create_subscription(TaskState, topics.STATE, self.on_state,
                                 qos.stream_qos(qos.STATE_QOS), event_callbacks=quiet_sub)
        if self.params.human_action_source == 'same_step':
            # only same_step reads the human's answers; with 'applied' (the default) a reader
            # here would cost the human node a delivery and this process a wake-up per step for
            # nothing (the recorder is then the topic's only reader)
            self.create_subscription(HumanAction, topics.HUMAN_ACTION, self.on_human_action,
                                     qos.HUMAN_ACTION_QOS, event_callbacks=quiet_sub)
        self.reset_client = self.create_client(ResetEpisode, topics.RESET_SERVICE)
        self.create_service(Trigger, PAUSE_SERVICE, self.on_pause)
        self.create_service(Trigger, RESUME_SERVICE, self.on_resume)
        self.create_service(Trigger, ABORT_SERVICE, self.on_abort)
        self.create_service(Trigger, STOP_FOR_INPUT_SERVICE, self.on_stop_for_input)
        self._create_input_hold()
        self.learner_health = LearnerHealth()
        DiagnosticsReporter(self, lambda: [self.learner_health.status(self.core,
                                                                      self.break_seconds())])

    def _init_state(self):
        """Set the node's bookkeeping of the episode loop to its start."""
        self.pause_requested = False
        self.next_episode_at = 0.0      # monotonic s: realtime break between episodes
        if self.params.resume_from:
            # a resumed session (after a lost joystick or an abort) gives the person
            # the same break, and the page its countdown, before the first episode
            self.next_episode_at = time.monotonic() + self.break_seconds()
        self.newest_state = None        # the newest state of the running episode (for abort)
        self.human_actions = {}         # stamp key -> normalized command
        self.latest_human_action = 0.0
        self.pending_state = None       # a state waiting for its human action (lockstep)
        self.pending_since = 0.0
        self.stamps = {}                # step -> stamp of the running episode's states
        self.states_before_limits = []  # states that came before the first reset response
        self.reset_requested_at = None
        self.reset_future = None
        self.reset_request = None       # the last reset asked for (asked again on retry)
        self.reset_retry_at = None      # monotonic s: ask again (the sim's writer not matched)
        self.state_readers_wanted = 0   # readers of /hrc/state the first reset waits for
        self.state_readers_since = None
        self.waiting_since = time.monotonic()
        self.named_nodes_since = None   # when the nodes of wait_for_subscribers were first seen
        self.exit_at = None
        self.exit_code = 0
        self.human_timeouts = 0
        self.step_gaps = 0
        self.checkpoint_dir = (os.path.join(self.params.checkpoint_dir, self.core.session_id)
                               if self.params.checkpoint_dir and self.practice is None else '')
        stale = remove_stale_temporaries(self.checkpoint_dir) if self.checkpoint_dir else []
        if stale:
            self.get_logger().info(f'removed {len(stale)} temporary files of a killed '
                                   f'checkpoint write in {self.checkpoint_dir}')

    # ------------------------------------------------------------------ session lifecycle

    def tick(self):
        """Start episodes when the sim is ready, time out human actions, exit when done."""
        now = time.monotonic()
        if self.exit_at is not None:
            if now >= self.exit_at:
                raise SystemExit(self.exit_code)
            return
        if self.practice is not None:
            self.practice_tick(now)
            return
        if self.core.phase == 'done':
            self.finish_session()  # a resumed session that had already finished
            return
        if self.core.phase == 'paused':
            return
        if self.reset_retry_at is not None and now >= self.reset_retry_at:
            self.reset_retry_at = None
            self.call_reset(self.reset_request)
        if not self.core.in_episode and self.reset_future is None:
            if self.core.phase == 'updating' or (now < self.next_episode_at and
                                                 self.next_clock_mode() == 'realtime'):
                return
            if self.ready_to_reset(now):
                self.start_episode()
        if self.pending_state is not None \
                and now - self.pending_since > self.params.human_action_timeout:
            state = self.pending_state
            self.human_timeouts += 1
            self.get_logger().warn(
                f'no human action for episode {state.episode} step {state.step} within '
                f'{self.params.human_action_timeout} s: acting on 0 '
                f'({self.human_timeouts} timeouts so far)', throttle_duration_sec=5.0)
            self.act(state, 0.0)  # same_step: the missing answer is observed as 0

    def call_reset(self, request) -> None:
        """Ask the sim to reset for ``request`` (kept, to ask again when the sim says retry)."""
        self.reset_request = request
        self.reset_future = self.reset_client.call_async(request)
        self.reset_future.add_done_callback(self.on_reset_done)

    def start_episode(self):
        """Begin the next episode in the core and ask the sim to reset for it."""
        # An update inside a realtime episode runs in a learner thread (the control step never
        # waits for it; new weights act from a later step boundary); lockstep episodes update
        # synchronously at the step where the update is due, exactly as the in-process engine.
        self.core.set_learner_mode('background' if self.next_clock_mode() == 'realtime'
                                   else 'synchronous')
        try:
            plan = self.core.start_episode()
        except PopulationStepRefused as error:   # partners first run without its pre-training
            self.abort(str(error), exit_code=2)
            return
        self.stamps = {}
        self.states_before_limits = []
        self.pending_state = None
        self.human_actions.clear()
        # Announce the episode (and its roles) before the sim publishes its first state, and
        # wait until every subscriber has it: a human node that saw the new episode's first
        # state before the announcement answered it with the old roles (a race of the graph,
        # seen under load at a role change and at the session's first state).
        self.publish_session(f'episode {episode_number(plan.episode)} '
                             f'{"(evaluation)" if plan.evaluation else ""} starting: '
                             + self.core.status_line())
        self.session_pub.wait_for_all_acked(Duration(seconds=ANNOUNCE_ACK_TIMEOUT_S))
        request = ResetEpisode.Request(seed=plan.seed, episode=plan.episode,
                                       clock_mode=self.next_clock_mode(),
                                       state_readers=self.state_readers_wanted)
        self.state_readers_wanted = 0   # the first episode only: the readers are matched then
        self.call_reset(request)

    def on_reset_done(self, future):
        """Report a refused reset (the states of the new episode arrive on /hrc/state)."""
        self.reset_future = None
        try:
            response = future.result()
        except Exception as error:  # the service call itself failed
            self.abort(f'reset call failed: {error}')
            return
        if not response.success and response.retry:   # only the first reset asks to wait
            now = time.monotonic()
            if now - self.state_readers_since > SESSION_MATCH_GRACE_S:
                self.get_logger().warning(
                    f'{response.message} after {SESSION_MATCH_GRACE_S:g} s: starting anyway')
                self.reset_request.state_readers = 0
            self.reset_retry_at = now + TICK_S
            return
        if not response.success:
            self.abort(f'the sim refused the reset: {response.message}')
            return
        limits = SimLimits.of(response)
        first = not self.core.limits_known
        try:
            changed = self.core.set_limits(limits)
        except ValueError as error:
            self.abort(f'{error} (in the reset response of {topics.RESET_SERVICE})')
            return
        if first:
            self.get_logger().info(f'from the sim: {limits.describe()}, clock '
                                   f'{response.clock_mode}')
        elif changed:
            self.get_logger().warning(f'the sim changed its limits mid-session: now '
                                      f'{limits.describe()}')
        early, self.states_before_limits = self.states_before_limits, []
        for state in early:
            self.on_state(state)

    def abort(self, reason: str, exit_code: int = 1):
        """End the session with phase ``aborted`` and ``exit_code`` (1: a failure)."""
        self.get_logger().error(f'session aborted: {reason}')
        self.core.abort()
        self.pending_state = None
        self.publish_session(f'aborted: {reason}')
        self.exit_code = exit_code
        self.exit_at = time.monotonic() + EXIT_LINGER_S

    # ------------------------------------------------------------------ operator controls

    def next_clock_mode(self) -> str:
        """Return the sim's clock for the next episode (ResetEpisode.clock_mode).

        The session's mode while the person acts; lockstep, without a break, while the robot
        practises alone, so the person does not wait for it (hrc_live).
        """
        return self.params.mode if self.core.human_involved else 'lockstep'

    def break_seconds(self) -> float:
        """Return the wall seconds of the break between episodes (realtime only)."""
        return self.params.episode_break if self.params.mode == 'realtime' else 0.0

    # ------------------------------------------------------------------ per step

    def on_human_action(self, msg: HumanAction):
        """Keep the human's command by stamp; act on a state that waited for it."""
        if not math.isfinite(msg.command):
            self.get_logger().warn(f'non-finite human action at step {msg.step} refused',
                                   throttle_duration_sec=5.0)
            return
        key = stamp_key(msg.header.stamp)
        self.human_actions[key] = float(msg.command)
        self.latest_human_action = float(msg.command)
        while len(self.human_actions) > HUMAN_ACTIONS_KEPT:
            self.human_actions.pop(next(iter(self.human_actions)))
        if self.pending_state is not None and stamp_key(self.pending_state.header.stamp) == key:
            self.act(self.pending_state, self.human_actions[key])

    def on_state(self, msg: TaskState):
        """Answer a state of the running episode (or close the episode on its final state)."""
        if self.practice is not None:
            self.on_practice_state(msg)
            return
        if not self.core.in_episode or self.core.phase not in ('training', 'evaluation'):
            return
        if msg.episode != self.core.episode:
            return  # a state of another episode (a late one, or a sim not reset by us)
        if not self.core.limits_known:
            # The sim publishes the episode's first state before its reset response arrives
            # here: act once the response has told us the limits (on_reset_done).
            self.states_before_limits.append(msg)
            return
        if msg.step in self.stamps:
            return  # already seen (duplicate delivery)
        expected = max(self.stamps) + 1 if self.stamps else 0
        if msg.step != expected:
            self.step_gaps += 1
            self.get_logger().warn(f'episode {msg.episode}: got step {msg.step}, expected '
                                   f'{expected} (states lost)', throttle_duration_sec=5.0)
        self.stamps[msg.step] = msg.header.stamp
        self.newest_state = msg
        if msg.truncated or msg.terminated:
            self.pending_state = None
            self.next_episode_at = time.monotonic() + self.break_seconds()
            self.finish_episode(msg)
            return
        if not self.core.needs_human_action:
            self.act(msg, None)  # the core observes the applied action, or 0 if not involved
            return
        key = stamp_key(msg.header.stamp)
        if key in self.human_actions:
            self.act(msg, self.human_actions[key])
        elif self.params.mode == 'realtime':
            self.act(msg, self.latest_human_action)
        else:
            self.pending_state = msg
            self.pending_since = time.monotonic()

    def act(self, msg: TaskState, human_action):
        """Decide, publish the wrench for this state, and the completed previous step."""
        self.pending_state = None
        decision = self.core.act(msg, human_action)
        wrench = WrenchStamped()
        wrench.header.stamp = msg.header.stamp
        wrench.header.frame_id = 'world'
        set_wrench_value(wrench.wrench, self.core.robot_dof, decision.wrench)
        self.wrench_pub.publish(wrench)
        if decision.previous is not None:
            self.publish_step(decision.previous)
        if decision.update is not None:
            self.log_update(decision.update, f'took over at episode {msg.episode} step '
                                             f'{msg.step}')

    def log_update(self, stats: dict, when: str):
        """Log one update's statistics; /diagnostics says the newest."""
        self.learner_health.on_update(stats)
        self.get_logger().info(update_line(stats, when, self.core.params.algorithm))

    def publish_step(self, record):
        """Publish one AgentStep (the state acted on, the action and the reward it earned)."""
        msg = AgentStep(**agent_step_fields(record))
        stamp = self.stamps.get(record.step)
        if stamp is not None:
            msg.header.stamp = stamp
        msg.header.frame_id = 'world'
        self.step_pub.publish(msg)

    # ------------------------------------------------------------------ per episode

    def finish_episode(self, final: TaskState):
        """Close the episode: summaries, update, checkpoint, session change, next reset."""
        step_before = self.core.training_step.index
        answer = self.human_actions.get(stamp_key(final.header.stamp)) \
            if self.core.needs_human_action else None
        result = self.core.end_episode(final, answer)
        if result.last_record is not None:
            self.publish_step(result.last_record)
        self.publish_episode(result, final)
        errors = ', '.join(f'{name} {value:.4f}' for name, value in result.errors.items())
        self.get_logger().info(
            f'episode {result.episode} {"evaluation " if result.evaluation else ""}'
            f'{"judging " if result.judging else ""}done: '
            f'{result.steps} steps, return {result.episode_return:.2f}, mean errors {errors}, '
            f'effort robot {result.robot_effort:.4f} human {result.human_effort:.4f}'
            f'{", condition met" if result.converged else ""}'
            f'{", human timeouts " + str(self.human_timeouts) if self.human_timeouts else ""}')
        if result.event == 'advanced':
            self.get_logger().info(f'training step {step_before + 1} converged after '
                                   f'{self.core.total_episodes} episodes; next: '
                                   + self.core.status_line())
        if self.core.phase == 'updating':
            self.publish_session(f'updating the policy after episode '
                                 f'{episode_number(result.episode)} '
                                 f'({self.core.buffered_samples} samples)')
            stats = self.core.update()
            if stats is not None:
                self.log_update(stats, f'after episode {result.episode}')
        if not self.save_checkpoint(LATEST_CHECKPOINT):
            return
        if result.event == 'training_finished':
            outcome = 'converged' if result.converged else 'not converged'
            self.get_logger().info(f'training finished after {self.core.total_episodes} '
                                   f'episodes ({self.core.human_involved_episodes} with the '
                                   f'human), {outcome}')
        if self.core.phase == 'done':
            self.finish_session()
            return
        if self.pause_requested:
            self.enter_pause()
            return
        self.publish_session(self.core.status_line())

    def publish_episode(self, result, final: TaskState):
        """Publish the EpisodeSummary of a finished episode."""
        msg = EpisodeSummary(**episode_summary_fields(self.core, result))
        msg.header.stamp = final.header.stamp
        msg.header.frame_id = 'world'
        self.episode_pub.publish(msg)

    def finish_session(self):
        """Log the evaluation, save the final checkpoint, announce ``done``, exit soon."""
        summary = self.core.evaluation_summary()
        if summary:
            metrics = ', '.join(f'{name} {value:.4f}' if isinstance(value, float)
                                else f'{name} {value}' for name, value in summary.items())
            self.get_logger().info(f'evaluation: {metrics}')
        if not self.save_checkpoint(FINAL_CHECKPOINT):
            return
        self.publish_session('session done: ' + self.core.status_line())
        self.get_logger().info(f'session {self.core.session_id} done')
        self.exit_at = time.monotonic() + EXIT_LINGER_S

    def save_checkpoint(self, name: str) -> bool:
        """Write a checkpoint into the session's checkpoint directory (if any).

        A write that fails (a full disk, a folder not writable) ends the session with exit
        code 1 and the reason: a session without its checkpoints cannot be resumed, and one
        without ``final.pt`` must not read as a success. Returns whether it was written.
        """
        if not self.checkpoint_dir:
            return True
        path = os.path.join(self.checkpoint_dir, name)
        try:
            save_checkpoint(self.core, path)
        except OSError as error:
            self.abort(f'checkpoint {path} not written: {os_error_text(error)}', exit_code=1)
            return False
        return True

    def publish_session(self, message: str):
        """Publish the SessionStatus (transient local: late joiners get the newest).

        In practice the practice's status (its own message), or ``message`` once aborted.
        """
        core = self.core
        if self.practice is not None:
            fields = self.practice.status()
            if core.phase == Phase.ABORTED:
                fields.update(phase=int(Phase.ABORTED), message=message)
            msg = SessionStatus(**fields)
            msg.header.stamp = self.get_clock().now().to_msg()
            self.session_pub.publish(msg)
            return
        msg = SessionStatus(**session_status_fields(core, message))
        msg.header.stamp = self.get_clock().now().to_msg()
        self.session_pub.publish(msg)

def main(args=None) -> int:
    """Run the agent node."""
    return run_node(AgentNode, 'agent_node', SUMMARY, AgentParams, args)


if __name__ == '__main__':
    import sys

    sys.exit(main())
