"""A hostile second publisher for the tests.

It floods a command topic with wrongly stamped commands (or giant ones) as fast as it can,
until killed.

    python flood.py <topic> <frame_id_bytes>
"""

import sys

from geometry_msgs.msg import WrenchStamped
from hrc_common import qos
import rclpy


def main() -> None:
    """Publish WrenchStamped on argv[1] with a frame_id of argv[2] bytes, stamped 12345 s."""
    topic, size = sys.argv[1], int(sys.argv[2])
    rclpy.init()
    node = rclpy.create_node('flooder')
    publisher = node.create_publisher(WrenchStamped, topic, qos.COMMAND_QOS)
    message = WrenchStamped()
    message.header.stamp.sec = 12345
    message.header.frame_id = 'x' * size
    message.wrench.torque.x = 0.4
    message.wrench.force.z = 1.5
    sent = 0
    try:
        while rclpy.ok():
            publisher.publish(message)
            sent += 1
            if sent % 1000 == 0:
                print(f'sent {sent}', flush=True)
    except KeyboardInterrupt:
        pass


if __name__ == '__main__':
    main()
