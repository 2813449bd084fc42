"""The QoS each topic of the session graph is published with: one pure table (no rclpy).

Every user reads this table: ``hrc_common.qos`` builds the rclpy profiles of the nodes from it,
the bag writers (``hrc_bag.session_writer``, the in-process engine) store it as the offered
QoS of a recording, and the synthetic session publishes with it. A deadline is a contract both
sides must offer/request alike (an offered deadline longer than the requested one makes the
pair incompatible), hence one table.
"""

from dataclasses import dataclass

from hrc_common import topics
from hrc_common.contract import NS_PER_S


@dataclass(frozen=True)
class TopicQoS:
    """The QoS of one topic: keep-last ``depth``, reliability, durability, deadline (ns)."""

    depth: int
    reliable: bool = True
    transient_local: bool = False
    deadline_ns: int = 0            # 0: no deadline


# A command stream that stays silent this long is reported by the deadline event. Between
# episodes the sim holds and no commands flow, so the event is informative, not an error.
COMMAND_DEADLINE_NS = NS_PER_S      # 1 s

# Keep-last depth of the writers of the recorded streams (state, commands, the human's action,
# the agent's step, joint states); readers keep the depths below. A reliable writer whose
# history is full drops the oldest sample even if a stalled reader has not received it: with
# the depths below a recorder stopped for seconds lost whole lockstep episodes. A lockstep sim
# that awaits its recorder stays within a window these histories hold
# (hrc_sim_node.recorder_gate.window_states), so all it published can still be retransmitted.
STREAM_WRITER_DEPTH = 1000

STATE = TopicQoS(depth=10)
COMMAND = TopicQoS(depth=1, deadline_ns=COMMAND_DEADLINE_NS)
HUMAN_ACTION = TopicQoS(depth=10)
SESSION = TopicQoS(depth=1, transient_local=True)
# Late joiners (the recorder, a report tool) get the recent episode summaries.
EPISODE = TopicQoS(depth=100, transient_local=True)
AGENT_STEP = TopicQoS(depth=10)
# robot_state_publisher's convention: the description latched for late joiners.
ROBOT_DESCRIPTION = TopicQoS(depth=1, transient_local=True)
JOINT_STATES = TopicQoS(depth=10)

# The QoS each topic of the session graph (hrc_common.topics.TYPES) is published with.
OF_TOPIC = {
    topics.STATE: STATE,
    topics.ROBOT_CMD_WRENCH: COMMAND,
    topics.HUMAN_CMD_WRENCH: COMMAND,
    topics.HUMAN_ACTION: HUMAN_ACTION,
    topics.SESSION: SESSION,
    topics.EPISODE: EPISODE,
    topics.AGENT_STEP: AGENT_STEP,
    topics.ROBOT_DESCRIPTION: ROBOT_DESCRIPTION,
    topics.JOINT_STATES: JOINT_STATES,
}
