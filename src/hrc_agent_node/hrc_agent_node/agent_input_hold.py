"""The agent node holds the session in its own process while the person's input is lost.

The session runner (``hrc_bringup.input_guard``) calls ``/hrc/agent/stop_for_input`` when the
person's joystick is lost while they act, and says why on ``/hrc/session/input_lost`` (empty
once the input is back). The agent then:

* answers the newest state with a zero wrench and drops the running episode (not learned from,
  not counted: the updates SAC made inside it are undone as well);
* takes up the session where its last finished episode left it: a fresh core loaded from
  ``latest.pt``, the same state a new agent process resuming from it would have (before this,
  the runner started a new agent process, 2-3 s of interpreter, torch and discovery);
* announces phase ``paused`` with the words of the loss, and "connected again" when the
  runner says the input is back; the sim holds (a paused status mid-episode holds it);
* refuses the operator's resume while the input is lost, and on resume runs the interrupted
  episode again from its start (the recorder files it as its next attempt).

A mixin of :class:`hrc_agent_node.agent_node.AgentNode`.
"""

import os

from hrc_common import qos, topics
from hrc_common.contract import Phase
from hrc_common.episode_numbers import episode_number
from hrc_common.session_control import STOPPED_FOR_INPUT
from std_msgs.msg import String

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import CheckpointError, load_into, load_session_start


class InputHold:
    """Hold for a lost input, in process (mixin of AgentNode; see the module docstring)."""

    def _create_input_hold(self) -> None:
        self.held_for_input = ''        # the words of the loss while held ('' = not held)
        self.input_lost_words = ''      # the runner's /hrc/session/input_lost ('' = present)
        self.create_subscription(String, topics.INPUT_LOST, self._on_input_lost,
                                 qos.SESSION_QOS, event_callbacks=qos.NO_SUBSCRIPTION_EVENTS)

    def _on_input_lost(self, message: String) -> None:
        self.input_lost_words = message.data
        if self.held_for_input:
            if message.data:
                self.held_for_input = message.data
            self._announce_hold()

    def _announce_hold(self) -> None:
        words = self.held_for_input
        self.publish_session(f'{words}; the joystick is connected again: paused, resume when '
                             f'ready' if not self.input_lost_words else
                             f'{words}: paused; resume after it is back')

    def hold_for_input(self, response):
        """Drop the running episode, take up the last finished one's state, pause; answer."""
        where = f'before episode {episode_number(self.core.episode)}'
        if self.core.in_episode and self.newest_state is not None:
            where = (f'in episode {episode_number(self.newest_state.episode)} at step '
                     f'{self.newest_state.step} (dropped, not learned from)')
        self.publish_zero_wrench(self.newest_state)
        try:
            taken_up = self._take_up_last_checkpoint()
        except CheckpointError as error:
            self.abort(f'{STOPPED_FOR_INPUT} {where}; {error}', exit_code=1)
            response.success, response.message = False, str(error)
            return response
        self._init_state()
        if self.core.phase in (Phase.TRAINING, Phase.EVALUATION):
            self.core.pause()
        self.held_for_input = self.input_lost_words or STOPPED_FOR_INPUT
        self._announce_hold()
        self.get_logger().warning(f'held for the lost input {where}; {taken_up}')
        response.success, response.message = True, f'held {where}; {taken_up}'
        return response

    def _take_up_last_checkpoint(self) -> str:
        """Replace the core by one loaded from latest.pt (a fresh one without it); say which."""
        old = self.core
        old.abort()                                  # the running episode is dropped
        old.set_learner_mode('synchronous')          # its learner threads stop
        core = AgentCore(self.params)
        checkpoint = self.latest_checkpoint_path()
        if checkpoint and os.path.exists(checkpoint):
            load_into(core, checkpoint, resume=True)
            words = (f'took up {checkpoint} ({core.total_episodes} training episodes): the '
                     f'interrupted episode runs again')
        else:   # what the session started from (resume_from, start_from), or nothing
            started = load_session_start(core)
            words = ('no episode had finished: the session starts again from its first'
                     + (f' ({started})' if started else ''))
        self.core = core
        return words

    def refuse_resume_for_input(self, response) -> bool:
        """Refuse the operator's resume while the held-for input is still lost."""
        if not self.held_for_input or not self.input_lost_words:
            return False
        response.success = False
        response.message = f'the joystick is still disconnected: {self.input_lost_words}'
        return True
