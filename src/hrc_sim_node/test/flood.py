"""A hostile second publisher for the tests.

It floods a command topic with wrongly stamped commands (or giant ones) at up to
``rate`` messages per second (never faster, also after a stall), until killed.

    python flood.py <topic> <frame_id_bytes> <rate>
"""

import sys
import time

from geometry_msgs.msg import WrenchStamped
from hrc_common import qos
import rclpy


def main() -> None:
    """Publish WrenchStamped on argv[1] with a frame_id of argv[2] bytes, stamped 12345 s."""
    topic, size, rate = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    rclpy.init()
    node = rclpy.create_node('flooder')
    publisher = node.create_publisher(WrenchStamped, topic, qos.COMMAND_QOS)
    message = WrenchStamped()
    message.header.stamp.sec = 12345
    message.header.frame_id = 'x' * size
    message.wrench.torque.x = 0.4
    message.wrench.force.z = 1.5
    period = 1.0 / rate
    due = time.monotonic()
    try:
        while rclpy.ok():
            publisher.publish(message)
            # Never faster than ``rate``: after a stall (a busy machine) the schedule restarts
            # instead of catching up in a burst that no bounded queue would hold.
            due = max(due + period, time.monotonic() - 0.001)
            ahead = due - time.monotonic()
            if ahead > 0.001:
                time.sleep(ahead)
    except KeyboardInterrupt:
        pass


if __name__ == '__main__':
    main()
