#!/usr/bin/env python3
"""Minimal reproduction: why the hrc nodes do not spin on rclpy's EventsExecutor.

    python bench/events_executor_hang.py          # from any directory, ~10 s

One node in one process, a subscription and a publisher on the same topic, served by rclpy's
``rclpy.experimental.EventsExecutor`` (Jazzy, rclpy 7.1). A second Python thread publishes three
messages, prints what was received and shuts the context down. Each way of turning the
executor runs in its own process, killed (SIGKILL) after a few seconds if it does not end:

* ``spin()`` (what ``rclpy.spin(node, executor)`` and every hrc node's main() called): no
  callback runs and the other Python thread never runs either (it prints nothing), the process
  does not end on shutdown and ignores SIGTERM (the executor catches SIGINT and SIGTERM itself);
* ``spin_once()`` without a timeout: the same;
* ``spin_once(timeout_sec=0.1)`` in a loop: the messages are received, the thread runs, the
  process ends.

So the executor's blocking wait without a timeout holds the interpreter (no other thread, no
callback): an rclpy bug (Jazzy, rclpy 7.1). It also has no guard conditions, which the human
node needs. Kept to check a newer rclpy before the executor is reconsidered (docs/engines.md,
"The nodes' executor").
"""

import subprocess
import sys

CHILD = r"""
import sys, threading, time
import rclpy
from rclpy.experimental import EventsExecutor
from std_msgs.msg import Int32
rclpy.init(domain_id=int(sys.argv[2]))
node = rclpy.create_node('events_hang')
received = []
node.create_subscription(Int32, '/events_hang', lambda message: received.append(message.data), 10)
publisher = node.create_publisher(Int32, '/events_hang', 10)
executor = EventsExecutor()
executor.add_node(node)

def feed():
    time.sleep(1.0)
    for index in range(3):
        publisher.publish(Int32(data=index))
        time.sleep(0.2)
    time.sleep(0.5)
    print(f'  other thread ran: received {received}', flush=True)
    rclpy.shutdown()

threading.Thread(target=feed, daemon=True).start()
try:
    if sys.argv[1] == 'spin()':
        executor.spin()
    elif sys.argv[1] == 'spin_once()':
        while rclpy.ok():
            executor.spin_once()
    else:
        while rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
except Exception as error:  # ExternalShutdownException once the thread shut rclpy down
    pass
print('  returned', flush=True)
"""


def main() -> int:
    """Run each way in a child process and say whether it worked."""
    for index, way in enumerate(('spin()', 'spin_once()', 'spin_once(timeout_sec=0.1)')):
        print(f'EventsExecutor.{way}:', flush=True)
        child = subprocess.Popen([sys.executable, '-c', CHILD, way, str(150 + index)])
        try:
            child.wait(timeout=6)
            print(f'  ended by itself (exit code {child.returncode})', flush=True)
        except subprocess.TimeoutExpired:
            child.terminate()
            try:
                child.wait(timeout=2)
                print('  hung; ended by SIGTERM', flush=True)
            except subprocess.TimeoutExpired:
                child.kill()
                child.wait()
                print('  hung: nothing received, the other thread never ran, SIGTERM '
                      'ignored; killed', flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
