"""Before the first episode: wait for the sim, the named readers and the session's readers.

The session runner names the nodes that must listen first (``wait_for_subscribers``: the human
node and the recorder), so the first state is recorded and answered with the session's roles
whatever the start-up order or the network. Every wait is bounded (``reset_timeout``, then
``SESSION_MATCH_GRACE_S``) and said in the log.

A mixin of :class:`hrc_agent_node.agent_node.AgentNode`.
"""

from hrc_common import topics
from rclpy.duration import Duration

# s: once the nodes of wait_for_subscribers are seen, how long every /hrc/session reader of the
# graph may take to match this node's writer before the first episode starts anyway.
SESSION_MATCH_GRACE_S = 10.0

class StartupWait:
    def ready_to_reset(self, now: float) -> bool:
        """Return True once the sim's reset service and the session's listeners are there.

        The session aborts when the service has not appeared after ``reset_timeout``.
        """
        if not self.reset_client.service_is_ready():
            if now - self.waiting_since > self.params.reset_timeout:
                self.abort(f'the reset service {topics.RESET_SERVICE} did not appear within '
                           f'{self.params.reset_timeout} s')
            return False
        return not self.missing_subscribers(now)

    def missing_subscribers(self, now: float) -> bool:
        """Return True while a node of ``wait_for_subscribers`` is not ready for the session.

        Ready: it subscribes to the states and to the session, every session reader the graph
        shows is matched by this node's session writer (so the announcement of the first
        episode reaches it before the reset: a human node that had not matched yet answered the
        first states with its default roles), and every matched reader has acknowledged the
        writer's history (the session's first announcement, sent to a late reader as
        transient-local history: the writer keeps one sample, so the next announcement would
        replace it before a slow reader had it, and the recorder's bag would lack it). Checked
        before the first episode of this process only; after ``reset_timeout`` the session
        aborts with the names.
        """
        wanted = {name for name in self.params.wait_for_subscribers if name}
        if not wanted or getattr(self, 'subscribers_seen', False):
            return False
        on_state = {info.node_name for info in self.get_subscriptions_info_by_topic(topics.STATE)}
        session_readers = self.get_subscriptions_info_by_topic(topics.SESSION)
        on_session = {info.node_name for info in session_readers}
        missing = sorted((wanted - on_state) | (wanted - on_session))
        matched = self.session_pub.get_subscription_count()
        if not missing:
            if self.named_nodes_since is None:
                self.named_nodes_since = now
            if matched >= len(session_readers) \
                    and self.session_pub.wait_for_all_acked(Duration(seconds=0)):
                self.subscribers_seen = True
                self.want_state_readers(now)
                return False
            if now - self.named_nodes_since > SESSION_MATCH_GRACE_S:
                # A reader that never matches (another type or QoS, e.g. a tool) must not hold
                # the session: the named nodes are there; go on and say so.
                self.get_logger().warning(
                    f'{len(session_readers)} readers of {topics.SESSION} in the graph, '
                    f'{matched} matched (not all acknowledging the first announcement) after '
                    f'{SESSION_MATCH_GRACE_S:g} s: starting anyway')
                self.subscribers_seen = True
                self.want_state_readers(now)
                return False
            return True
        if now - self.waiting_since > self.params.reset_timeout:
            self.abort(f'{", ".join(missing)} did not subscribe to {topics.STATE} and '
                       f'{topics.SESSION} within {self.params.reset_timeout} s')
        return True

    def want_state_readers(self, now: float) -> None:
        """Ask the first reset to wait until the sim has matched every reader of the states.

        The readers this node's graph shows (itself, the human node, the recorder, a display)
        may not all be matched by the sim's writer yet: discovery runs pairwise, and a recorder
        the sim found late missed the first lockstep episodes (seen under load: episodes 0-4,
        0.35 s in all, were not in the bag). A reader that never matches gets
        SESSION_MATCH_GRACE_S.
        """
        self.state_readers_wanted = len(self.get_subscriptions_info_by_topic(topics.STATE))
        self.state_readers_since = now
