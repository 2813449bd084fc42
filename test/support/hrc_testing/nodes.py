"""Helpers for tests that run hrc nodes as separate processes over real DDS.

Each test gets its own ``ROS_DOMAIN_ID`` (reserved by ``hrc_common.domains.DomainReservation``,
see conftest.py's fixtures) and discovery limited to localhost, so tests never see each other's
nodes. A node is started exactly as ``ros2 run`` would: the executable found under
``<prefix>/lib/<package>/`` through the ament index.
"""

import collections
import os
import pathlib
import signal
import subprocess
import tempfile
import time

from hrc_common.executables import executable_path


def ros_environment(domain_id: int) -> dict:
    """Return os.environ with the test's domain id and localhost-only discovery."""
    env = dict(os.environ)
    env['ROS_DOMAIN_ID'] = str(domain_id)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env.pop('ROS_LOCALHOST_ONLY', None)
    env['PYTHONUNBUFFERED'] = '1'
    # Tests kill nodes on purpose; Fast DDS's shared-memory transport can then leave matched
    # endpoints that exchange no data for a minute (eProsima/Fast-DDS#1144, #5053). UDP on
    # loopback has no such state to go stale.
    env['FASTDDS_BUILTIN_TRANSPORTS'] = 'UDPv4'
    return env


class NodeProcess:
    """A node executable running in its own process; its output goes to a temporary file."""

    def __init__(self, package, executable, args=(), env=None, parameters=None,
                 params_file=None, ros_args=()):
        command = [str(executable_path(package, executable)), *args]
        ros_section = list(ros_args)
        if params_file is not None:
            ros_section += ['--params-file', str(params_file)]
        for name, value in (parameters or {}).items():
            ros_section += ['-p', f'{name}:={format_parameter(value)}']
        if ros_section:
            command += ['--ros-args', *ros_section]
        self.command = command
        self.name = f'{package}/{executable}'
        self._log = tempfile.NamedTemporaryFile(prefix=f'{executable}-', suffix='.log',
                                                delete=False)
        self.process = subprocess.Popen(command, env=env, stdout=self._log,
                                        stderr=subprocess.STDOUT, start_new_session=True)

    @property
    def output(self) -> str:
        """Everything the process printed so far."""
        return pathlib.Path(self._log.name).read_text(errors='replace')

    def wait(self, timeout: float) -> int:
        """Wait for the process to exit and return its exit code."""
        return self.process.wait(timeout=timeout)

    def remove_log(self) -> None:
        """Delete the output file (after the test: a run of the suite made ~50 in /tmp)."""
        self._log.close()
        pathlib.Path(self._log.name).unlink(missing_ok=True)

    def stop(self, timeout: float = 10.0) -> int:
        """SIGINT the process (as Ctrl-C would), then SIGKILL its group if it hangs."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait(timeout=timeout)
        return self.process.returncode


def format_parameter(value) -> str:
    """Format a Python value for ``-p name:=value`` (YAML syntax)."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, (list, tuple)):
        return '[' + ','.join(format_parameter(item) for item in value) + ']'
    if isinstance(value, str):
        return value if value else "''"
    return repr(value)


def wait_for(condition, timeout: float, interval: float = 0.02, spin=None) -> bool:
    """Poll ``condition()`` (spinning ``spin()`` in between if given) until true or timeout."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if spin is not None:
            spin()
        if condition():
            return True
        if spin is None:
            time.sleep(interval)
    return condition()


def serve_sim_parameters(context, limits, name: str = 'sim'):
    """Return a node ``name`` declaring the sim's period and limits, as the sim node does.

    For tests that run a human node without a sim: the node reads ``control_period``,
    ``max_force`` and ``max_torque`` from ``/<name>/get_parameters`` before it answers states.
    ``limits``: an ``hrc_common.contract.SimLimits``. The caller spins the node (add it to the
    test's executor) and destroys it.
    """
    import rclpy  # lazy: rclpy (0.3 s), the other helpers serve pure tests too

    node = rclpy.create_node(name, context=context)
    for field in limits.NAMES:
        node.declare_parameter(field, float(getattr(limits, field)))
    # The human's period, as the sim declares it (the human acts once a period when unset).
    node.declare_parameter('human_period', float(limits.human_step))
    return node


def read_bag_with_rosbags(typestore, folder) -> dict:
    """Read a rosbag2 folder with rosbags: {topic: [decoded messages]}."""
    from rosbags.rosbag2 import Reader  # lazy: rosbags (0.25 s), a test-only dependency

    messages = collections.defaultdict(list)
    with Reader(folder) as reader:
        for connection, _, raw in reader.messages():
            messages[connection.topic].append(
                typestore.deserialize_cdr(raw, connection.msgtype))
    return messages


def node_pid(executable: str, domain_id: int) -> int:
    """Return the pid of the process running ``executable`` on ``domain_id`` (0 if none).

    The nodes of ``hrc session`` run as separate processes; a test that stops one (SIGSTOP) to
    freeze it finds it by its command line and its ROS_DOMAIN_ID.
    """
    for entry in pathlib.Path('/proc').iterdir():
        try:
            command = (entry / 'cmdline').read_bytes()
            environment = (entry / 'environ').read_bytes().split(b'\0')
        except (OSError, ValueError):
            continue
        if (executable.encode() in command
                and f'ROS_DOMAIN_ID={domain_id}'.encode() in environment):
            return int(entry.name)
    return 0
