"""QoS profiles of the hrc topics, one place so publishers and subscribers always match.

A deadline is a contract both sides must offer/request alike (an offered deadline longer than
the requested one makes the pair incompatible), hence the shared constants.
"""

from hrc_common import topics
from rclpy.duration import Duration
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy,
                       qos_profile_sensor_data)

# A command stream that stays silent this long (s) is reported by the deadline event.
# Between episodes the sim holds and no commands flow, so the event is informative, not an error.
COMMAND_DEADLINE_S = 1.0

STATE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                       reliability=ReliabilityPolicy.RELIABLE)
COMMAND_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                         reliability=ReliabilityPolicy.RELIABLE,
                         deadline=Duration(seconds=COMMAND_DEADLINE_S))
HUMAN_ACTION_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                              reliability=ReliabilityPolicy.RELIABLE)
SESSION_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
# Late joiners (the recorder, a report tool) get the recent episode summaries.
EPISODE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
AGENT_STEP_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                            reliability=ReliabilityPolicy.RELIABLE)
JOY_QOS = qos_profile_sensor_data
# Visualization (image, markers): best effort, only the newest matters.
VISUAL_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                        reliability=ReliabilityPolicy.BEST_EFFORT)

# The profile each topic of the session graph (hrc_common.topics.TYPES) is published with.
OF_TOPIC = {
    topics.STATE: STATE_QOS,
    topics.ROBOT_CMD_WRENCH: COMMAND_QOS,
    topics.HUMAN_CMD_WRENCH: COMMAND_QOS,
    topics.HUMAN_ACTION: HUMAN_ACTION_QOS,
    topics.SESSION: SESSION_QOS,
    topics.EPISODE: EPISODE_QOS,
    topics.AGENT_STEP: AGENT_STEP_QOS,
}
# Publishers and subscriptions of the control loop without QoS event handlers (rclpy's defaults
# log incompatible QoS): each handler is an entity of the wait set rclpy's executor rebuilds at
# every turn, about 20 us per handler per turn (bench/wait_set_cost.py); the profiles above are
# the one contract, so incompatible QoS cannot arise between the hrc nodes.
NO_PUBLISHER_EVENTS = PublisherEventCallbacks(use_default_callbacks=False)
NO_SUBSCRIPTION_EVENTS = SubscriptionEventCallbacks(use_default_callbacks=False)
