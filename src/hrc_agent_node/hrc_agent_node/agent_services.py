"""The agent node's operator services: pause, resume and abort a session.

Operator controls (``std_srvs/Trigger``, names in ``hrc_common.session_control``):

* ``/hrc/agent/pause``: takes effect at the next episode boundary (after the update and the
  checkpoint): phase ``paused`` is announced and no reset is called until resumed;
* ``/hrc/agent/resume``: continues (or cancels a pause that has not taken effect yet);
* ``/hrc/agent/abort``: immediate: a zero wrench answers the newest state, phase ``aborted`` is
  announced, nothing more is answered, the checkpoint of the last episode end (latest.pt) is
  kept as it is, and the node exits with code ``EXIT_OPERATOR_ABORT`` (3). (A service call waits
  for a PPO update in progress, which takes about a second.)
* ``/hrc/agent/stop_for_input``: called by the session runner for a lost joystick: the
  session is held in this process (:mod:`hrc_agent_node.agent_input_hold`) until the
  operator's resume once the input is back; in the practice it stops as an abort does.

A mixin of :class:`hrc_agent_node.agent_node.AgentNode` (its core, publishers and exit).
"""

import os
import time

from geometry_msgs.msg import WrenchStamped
from hrc_common.episode_numbers import episode_number
from hrc_common.session_control import EXIT_OPERATOR_ABORT, LATEST_CHECKPOINT, STOPPED_FOR_INPUT

# Wall seconds between the last message and the exit, so reliable subscribers receive it.
EXIT_LINGER_S = 0.5
# Wall seconds to wait for every subscriber to acknowledge an episode's announcement.
ANNOUNCE_ACK_TIMEOUT_S = 0.5
PRACTICE_NO_PAUSE = ('the practice does not pause: it ends after its episodes (abort stops '
                     'it)')

class OperatorServices:
    def on_pause(self, request, response):
        """Pause at the next episode boundary (at once when between episodes)."""
        phase = self.core.phase
        if self.practice is not None:
            response.success, response.message = False, PRACTICE_NO_PAUSE
        elif self.exit_at is not None or phase in ('done', 'aborted'):
            response.success, response.message = False, f'cannot pause: the session is {phase}'
        elif phase == 'paused':
            response.success, response.message = True, 'already paused'
        elif self.core.in_episode or self.reset_future is not None:
            self.pause_requested = True
            response.success = True
            response.message = (f'pause requested: the session pauses when episode '
                                f'{episode_number(self.core.episode)} ends')
            self.publish_session(f'pause requested: the session pauses when episode '
                                 f'{episode_number(self.core.episode)} ends; '
                                 + self.core.status_line())
        else:
            self.enter_pause()
            response.success = True
            response.message = f'paused before episode {episode_number(self.core.episode)}'
        self.get_logger().info(f'operator pause: {response.message}')
        return response

    def enter_pause(self):
        """Pause the core between two episodes and announce it."""
        self.pause_requested = False
        self.core.pause()
        self.publish_session(f'paused by the operator before episode '
                             f'{episode_number(self.core.episode)}: '
                             + self.core.status_line())

    def on_resume(self, request, response):
        """Resume a paused session (or cancel a pause that has not taken effect)."""
        if self.practice is not None:
            response.success, response.message = False, PRACTICE_NO_PAUSE
        elif self.refuse_resume_for_input(response):
            pass
        elif self.core.phase == 'paused':
            self.held_for_input = ''
            self.core.resume()
            # A person gets the same break before the next episode as after an episode.
            self.next_episode_at = time.monotonic() + self.break_seconds()
            response.success = True
            response.message = f'resumed: episode {episode_number(self.core.episode)} starts next'
            self.publish_session('resumed by the operator: ' + self.core.status_line())
        elif self.pause_requested:
            self.pause_requested = False
            response.success, response.message = True, 'pause request cancelled'
            self.publish_session('pause request cancelled: ' + self.core.status_line())
        else:
            response.success = False
            response.message = f'not paused (phase {self.core.phase})'
        self.get_logger().info(f'operator resume: {response.message}')
        return response

    def on_abort(self, request, response):
        """Stop now: zero wrench, phase aborted, keep the last checkpoint, exit code 3."""
        return self._stop_now(response, 'by the operator')

    def on_stop_for_input(self, request, response):
        """Hold the session for the session runner's lost joystick (the practice: stop)."""
        if self.practice is not None or self.exit_at is not None:
            return self._stop_now(response, STOPPED_FOR_INPUT)
        if self.held_for_input:
            response.success, response.message = True, f'already held: {self.held_for_input}'
            return response
        return self.hold_for_input(response)

    def _stop_now(self, response, who: str):
        """Abort the session now (``who``: by whom and why, in the aborted status)."""
        if self.exit_at is not None:
            response.success = False
            response.message = f'the session is already ending (phase {self.core.phase})'
            return response
        if self.practice is not None:   # the robot never acted: nothing to zero or to keep
            where = f'in the practice ({self.practice.done} of {self.practice.episodes} done)'
            self.abort(f'{who} {where}', EXIT_OPERATOR_ABORT)
            response.success, response.message = True, f'aborted {where}'
            return response
        where = f'before episode {episode_number(self.core.episode)}'
        if self.core.in_episode and self.newest_state is not None:
            where = (f'in episode {episode_number(self.newest_state.episode)} at step '
                     f'{self.newest_state.step} (dropped, not learned from)')
        self.publish_zero_wrench(self.newest_state)
        checkpoint = self.latest_checkpoint_path()
        if checkpoint and os.path.exists(checkpoint):
            resume = f'resume from {checkpoint} ({self.core.total_episodes} training episodes)'
        else:
            resume = 'no checkpoint yet: a new session starts from scratch'
        self.abort(f'{who} {where}; {resume}', EXIT_OPERATOR_ABORT)
        response.success, response.message = True, f'aborted {where}; {resume}'
        return response

    def publish_zero_wrench(self, state):
        """Send a zero wrench answering ``state`` (the newest state; None: stamp 0).

        In realtime the sim applies the newest command whatever its stamp; in lockstep the
        stamp makes it the answer to the state the sim waits on.
        """
        wrench = WrenchStamped()
        if state is not None:
            wrench.header.stamp = state.header.stamp
        wrench.header.frame_id = 'world'
        self.wrench_pub.publish(wrench)

    def latest_checkpoint_path(self) -> str:
        """Return the path of the episode-end checkpoint ('' without checkpoints)."""
        return os.path.join(self.checkpoint_dir, LATEST_CHECKPOINT) if self.checkpoint_dir \
            else ''
