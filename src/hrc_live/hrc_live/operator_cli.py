"""Operator controls of a running session: pause, resume, abort, status.

    hrc operator pause      # at the end of the running episode
    hrc operator resume
    hrc operator abort      # now: zero commands, bags closed, resumable
    hrc operator status

``pause``/``resume``/``abort`` call the agent's ``std_srvs/Trigger`` services
(``hrc_common.session_control``) and print the agent's answer; ``status`` prints the newest
``/hrc/session`` (transient local, so it is there at once). Exit codes: 0 done, 1 refused by
the agent (the message says why), 4 no agent answered within ``--timeout``, 2 bad usage.
"""

import argparse
import sys
import time

from hrc_common.episode_numbers import episode_number
from hrc_common.contract import dof_name, phase_label
from hrc_common import topics
from hrc_common.session_control import OPERATOR_SERVICES

EXIT_REFUSED = 1
# s ``status`` waits for the agent's status once the runner has said what it waits for
RUNNER_WORD_GRACE_S = 1.0
EXIT_NO_AGENT = 4


def parse_args(argv=None):
    """Parse the command line."""
    parser = argparse.ArgumentParser(
        prog='hrc operator', description='Pause, resume or abort the running hrc session, or show '
        'its status. Pause and resume take effect at the next episode boundary; abort is '
        'immediate (zero commands, bags closed, resumable from the last checkpoint).')
    parser.add_argument('command', choices=('pause', 'resume', 'abort', 'status'),
                        help='pause, resume or abort the running session, or show its status')
    parser.add_argument('--timeout', type=float, default=10.0,
                        help='seconds to wait for the agent (default 10)')
    parser.add_argument('--domain-id', type=int, default=None,
                        help='ROS_DOMAIN_ID of the session (default: the environment)')
    options = parser.parse_args(argv)
    if options.timeout <= 0:
        parser.error('--timeout must be > 0')
    return options


def describe_status(status) -> str:
    """Return the lines ``operator status`` prints for a SessionStatus."""
    phase = phase_label(status.phase, str(status.phase))
    human = (f'involved on {list(status.human_subtasks)}' if status.human_involved
             else 'not involved')
    return '\n'.join([
        f'session {status.session_id}: case {status.case_id} ({status.strategy}), phase {phase}',
        f'training step {status.training_step + 1}/{max(status.training_step_count, 1)}; '
        f'robot drives {dof_name(status.robot_dof, "?")}, human '
        f'drives {dof_name(status.human_dof, "?")} ({human})',
        f'episode {episode_number(status.episode)}; {status.total_episodes} training episodes '
        'done, '
        f'{status.human_involved_episodes} with the human',
        f'{status.message}'])


def call_service(node, executor, name: str, timeout: float):
    """Call a Trigger service; return the response, or None if nobody answered in time."""
    from std_srvs.srv import Trigger  # lazy: rclpy (via the message), --help stays light

    client = node.create_client(Trigger, name)
    deadline = time.monotonic() + timeout
    while not client.wait_for_service(timeout_sec=0.1):
        if time.monotonic() > deadline:
            return None
    future = client.call_async(Trigger.Request())
    executor.spin_until_future_complete(future, timeout_sec=max(0.1, deadline -
                                                                time.monotonic()))
    return future.result() if future.done() else None


def wait_for_status(node, executor, timeout: float) -> tuple:
    """Return the newest SessionStatus (transient local) or None, and what the runner waits for.

    While the session runner waits (for the person's input, for the agent it starts again
    after a resume) /hrc/session may have no writer; the runner's word on
    /hrc/session/runner_waiting then answers after RUNNER_WORD_GRACE_S.
    """
    from hrc_common import qos  # lazy: rclpy, --help stays light
    from hrc_msgs.msg import SessionStatus  # lazy: rclpy (via the message), as above
    from std_msgs.msg import String  # lazy: as above

    received, waiting = [], []
    node.create_subscription(SessionStatus, topics.SESSION, received.append, qos.SESSION_QOS)
    node.create_subscription(String, topics.RUNNER_WAITING,
                             lambda message: waiting.append(message.data), qos.SESSION_QOS)
    start = time.monotonic()
    while not received and time.monotonic() < start + timeout:
        if waiting and waiting[-1] and time.monotonic() > start + RUNNER_WORD_GRACE_S:
            break
        executor.spin_once(timeout_sec=0.1)
    executor.spin_once(timeout_sec=0.1)     # the other topic's newest, if it is on its way
    return (received[-1] if received else None), (waiting[-1] if waiting else '')


def main(argv=None) -> int:
    """Entry point of ``hrc operator``."""
    options = parse_args(sys.argv[1:] if argv is None else argv)
    import rclpy  # lazy: rclpy (0.3 s), --help and a bad argument answer without it
    from rclpy.context import Context  # lazy: rclpy, as above

    context = Context()
    rclpy.init(context=context, domain_id=options.domain_id,
               signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    node = rclpy.create_node('operator', context=context)
    executor = rclpy.executors.SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        if options.command == 'status':
            status, waiting = wait_for_status(node, executor, options.timeout)
            if status is None and not waiting:
                print(f'no session status on /hrc/session within {options.timeout} s: is a '
                      f'session running (same ROS_DOMAIN_ID)?', file=sys.stderr)
                return EXIT_NO_AGENT
            if status is not None:
                print(describe_status(status))
            if waiting:
                print(f'the session runner: {waiting}')
            return 0
        service = OPERATOR_SERVICES[options.command]
        response = call_service(node, executor, service, options.timeout)
        if response is None:
            print(f'{options.command}: no answer from {service} within {options.timeout} s: '
                  f'is a session running (same ROS_DOMAIN_ID)?', file=sys.stderr)
            return EXIT_NO_AGENT
        if not response.success:
            print(f'{options.command} refused: {response.message}', file=sys.stderr)
            return EXIT_REFUSED
        print(f'{options.command}: {response.message}')
        return 0
    except KeyboardInterrupt:
        return 130
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown(context=context)


if __name__ == '__main__':
    sys.exit(main())
