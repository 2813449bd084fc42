"""The agent node's practice: N episodes of the person alone instead of a session.

With ``practice_episodes`` N > 0 (the session runner's ``--practice N``) the node announces the
practice on ``/hrc/session`` (strategy ``practice``), resets the sim for each episode in
realtime ``episode_break`` apart, answers no state (the robot does not act, nothing is learned
or checkpointed), publishes an ``EpisodeSummary`` of kind practice at each episode's end and
exits 0 after the last. What the practice counts and reports is ``practice.PracticeRun``'s.

A mixin of :class:`hrc_agent_node.agent_node.AgentNode`.
"""

import time

from hrc_agent_node.agent_services import ANNOUNCE_ACK_TIMEOUT_S, EXIT_LINGER_S
from hrc_common.contract import Phase
from hrc_msgs.msg import EpisodeSummary, TaskState
from hrc_msgs.srv import ResetEpisode
from rclpy.duration import Duration

class PracticeEpisodes:
    def practice_tick(self, now: float):
        """Start the next practice episode once the sim, the listeners and the break allow."""
        if self.practice.in_episode or self.reset_future is not None \
                or now < self.next_episode_at or self.core.phase == Phase.ABORTED:
            return
        if not self.ready_to_reset(now):
            return
        reset = self.practice.start_episode()
        # As for a session's episode: every listener has the announcement before the state.
        self.publish_session('')
        self.session_pub.wait_for_all_acked(Duration(seconds=ANNOUNCE_ACK_TIMEOUT_S))
        self.reset_future = self.reset_client.call_async(ResetEpisode.Request(
            seed=reset.seed, episode=reset.episode, clock_mode=reset.clock_mode))
        self.reset_future.add_done_callback(self.on_reset_done)

    def on_practice_state(self, msg: TaskState):
        """Follow a practice episode (no answer: the robot does not act); close it at its end."""
        if self.core.phase == Phase.ABORTED:
            return
        fields = self.practice.on_state(msg)
        if fields is None:
            return
        summary = EpisodeSummary(**fields)
        summary.header.stamp = msg.header.stamp
        summary.header.frame_id = 'world'
        self.episode_pub.publish(summary)
        self.get_logger().info(
            f'practice episode {summary.episode} done: {summary.steps} steps, mean errors '
            f'slider {summary.slider_error:.4f} pendulum {summary.pendulum_error:.4f} ball '
            f'{summary.ball_error:.4f}')
        self.publish_session('')
        if self.practice.finished:
            self.get_logger().info(f'practice done: {self.practice.done} episodes')
            self.exit_at = time.monotonic() + EXIT_LINGER_S
        else:
            self.next_episode_at = time.monotonic() + self.params.episode_break
