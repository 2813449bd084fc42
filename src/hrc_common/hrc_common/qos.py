"""rclpy QoS profiles of the hrc topics, built from the one table ``hrc_common.qos_table``.

The table (pure, no rclpy) says what each topic offers; this module turns it into the
``QoSProfile`` objects the nodes create their publishers and subscriptions with, so
publishers, subscribers and recordings always agree.
"""

from hrc_common import qos_table
from hrc_common.contract import NS_PER_S
from rclpy.duration import Duration
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy,
                       qos_profile_sensor_data)

COMMAND_DEADLINE_S = qos_table.COMMAND_DEADLINE_NS / NS_PER_S


def profile_of(spec: qos_table.TopicQoS) -> QoSProfile:
    """Return the rclpy profile of one row of the QoS table."""
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST, depth=spec.depth,
        reliability=(ReliabilityPolicy.RELIABLE if spec.reliable
                     else ReliabilityPolicy.BEST_EFFORT),
        durability=(DurabilityPolicy.TRANSIENT_LOCAL if spec.transient_local
                    else DurabilityPolicy.VOLATILE),
        deadline=Duration(nanoseconds=spec.deadline_ns))


def stream_qos(profile: QoSProfile) -> QoSProfile:
    """Return ``profile`` with the depth of a recorded stream (STREAM_WRITER_DEPTH).

    For the streams' writers (a stalled recorder gets what it missed retransmitted) and for a
    reader that must see every message after a stall (the agent's states: each carries the
    flags of the commands the sim counted missing). Depth is not part of QoS matching.
    """
    return QoSProfile(history=profile.history, depth=qos_table.STREAM_WRITER_DEPTH,
                      reliability=profile.reliability, durability=profile.durability,
                      deadline=profile.deadline)


STATE_QOS = profile_of(qos_table.STATE)
COMMAND_QOS = profile_of(qos_table.COMMAND)
HUMAN_ACTION_QOS = profile_of(qos_table.HUMAN_ACTION)
SESSION_QOS = profile_of(qos_table.SESSION)
EPISODE_QOS = profile_of(qos_table.EPISODE)
AGENT_STEP_QOS = profile_of(qos_table.AGENT_STEP)
JOY_QOS = qos_profile_sensor_data
# Visualization (image, markers): best effort, only the newest matters.
# /hrc/recorder/progress: only the newest acknowledgement matters.
RECORDER_PROGRESS_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                                   reliability=ReliabilityPolicy.RELIABLE)
VISUAL_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                        reliability=ReliabilityPolicy.BEST_EFFORT)

# The profile each topic of the session graph (hrc_common.topics.TYPES) is published with.
OF_TOPIC = {topic: profile_of(spec) for topic, spec in qos_table.OF_TOPIC.items()}
# Publishers and subscriptions of the control loop without QoS event handlers (rclpy's defaults
# log incompatible QoS): each handler is an entity of the wait set rclpy's executor rebuilds at
# every turn, about 20 us per handler per turn (bench/wait_set_cost.py); the profiles above are
# the one contract, so incompatible QoS cannot arise between the hrc nodes.
NO_PUBLISHER_EVENTS = PublisherEventCallbacks(use_default_callbacks=False)
NO_SUBSCRIPTION_EVENTS = SubscriptionEventCallbacks(use_default_callbacks=False)
