"""A node started by hand ends with its session: it exits once the agent says the session is done.

``hrc session`` stops the nodes it starts itself, in its order (the recorder last), and turns
this off for them (``exit_after_session: false``); a sim, human node or recorder started by
hand with ``ros2 run`` would otherwise stay up after the agent is done. An operator's abort
keeps them up: the session may be resumed (``--resume-from``) against the same nodes.
"""

from hrc_common import qos, topics
from hrc_common.contract import Phase
from hrc_msgs.msg import SessionStatus

# Seconds between the agent's "done" and the exit: the last messages of the session (its final
# status, a late summary) are still taken, and a recorder writes them before it closes.
SESSION_END_GRACE_S = 2.0


class SessionEndWatch:
    """Shuts ``node``'s context down ``grace`` s after the first SessionStatus with phase done."""

    def __init__(self, node, enabled: bool, grace: float = SESSION_END_GRACE_S):
        self.node, self.grace = node, grace
        self.ending = False
        if enabled:
            node.create_subscription(SessionStatus, topics.SESSION, self._on_status,
                                     qos.SESSION_QOS)

    def _on_status(self, status) -> None:
        if self.ending or status.phase != int(Phase.DONE):
            return
        self.ending = True
        self.node.get_logger().info(
            f'session {status.session_id!r} is done: exiting in {self.grace:.0f} s '
            f'(exit_after_session; hrc session turns it off for its own nodes)')
        self._timer = self.node.create_timer(self.grace, self._exit)

    def _exit(self) -> None:
        self._timer.cancel()
        self.node.context.try_shutdown()
