"""The stamp of a CDR-serialized message whose first field is a std_msgs/Header (no rclpy).

The sim reads each command's stamp, and the recorder each state's, from the bytes before
anything is decoded (a decode costs ten times more and is not needed to route or match).
"""

import struct


def header_stamp(data: bytes) -> tuple:
    """Return (sec, nanosec) of a CDR message that starts with a std_msgs/Header.

    The header's stamp comes first, after the 4-byte encapsulation (byte 1: 1 = little
    endian). Too short: (-1, 0), which no state carries.
    """
    if len(data) < 12:
        return -1, 0
    return struct.unpack_from('<iI' if data[1] == 1 else '>iI', data, 4)
