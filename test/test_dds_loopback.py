"""With discovery limited to LOCALHOST, DDS listens on loopback only (params/fastdds/loopback.xml).

`scripts/env.sh` points Fast DDS at the loopback profile when the discovery range is LOCALHOST.
A real sim node is started with the environment env.sh makes, and the UDP sockets it holds are
read from /proc: every DDS receive port of its domain (discovery and user data, 7400 + 250 *
domain + ...) must be bound to 127.0.0.1. The same node without the profile binds them to
0.0.0.0 (the control: the check can fail).
"""

import os
import pathlib
import subprocess
import time

from hrc_common.executables import executable_path

REPO = pathlib.Path(__file__).resolve().parents[1]


def env_sh_environment() -> dict:
    """Return the environment `source scripts/env.sh` makes, from a neutral directory."""
    script = f'source {REPO / "scripts" / "env.sh"} >/dev/null 2>&1 && env -0'
    env = {key: value for key, value in os.environ.items()
           if key not in ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE',
                          'ROS_AUTOMATIC_DISCOVERY_RANGE')}
    result = subprocess.run(['bash', '-c', script], cwd='/tmp', env=env, capture_output=True,
                            check=True)
    pairs = [item.split(b'=', 1) for item in result.stdout.split(b'\0') if b'=' in item]
    return {key.decode(): value.decode() for key, value in pairs}


def udp_sockets(pid: int) -> list:
    """Return [(address, port)] of the UDP sockets process ``pid`` holds (IPv4)."""
    inodes = set()
    for fd in os.listdir(f'/proc/{pid}/fd'):
        try:
            target = os.readlink(f'/proc/{pid}/fd/{fd}')
        except OSError:
            continue
        if target.startswith('socket:['):
            inodes.add(target[8:-1])
    sockets = []
    for line in pathlib.Path(f'/proc/{pid}/net/udp').read_text().splitlines()[1:]:
        fields = line.split()
        if fields[9] in inodes:
            address, port = fields[1].split(':')
            octets = [str(int(address[index:index + 2], 16)) for index in (6, 4, 2, 0)]
            sockets.append(('.'.join(octets), int(port, 16)))
    return sockets


def dds_ports_of_a_running_sim(env: dict, domain_id: int) -> list:
    """Start a sim node, wait until it holds its DDS sockets; return those of its domain."""
    env = dict(env, ROS_DOMAIN_ID=str(domain_id))
    process = subprocess.Popen([str(executable_path('hrc_sim_node', 'sim_node'))], env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        base = 7400 + 250 * domain_id     # the domain's port range (RTPS well-known ports)
        deadline = time.monotonic() + 30
        ports = []
        while time.monotonic() < deadline:
            ports = [(address, port) for address, port in udp_sockets(process.pid)
                     if base <= port < base + 250]
            if len(ports) >= 2:
                time.sleep(0.5)   # every participant's ports open together
                return [(address, port) for address, port in udp_sockets(process.pid)
                        if base <= port < base + 250]
            time.sleep(0.2)
        return ports
    finally:
        process.terminate()
        process.wait(timeout=15)


def test_env_sh_binds_dds_to_loopback_when_the_range_is_localhost(ros_domain_id):
    env = env_sh_environment()
    assert env['ROS_AUTOMATIC_DISCOVERY_RANGE'] == 'LOCALHOST'
    assert env['FASTRTPS_DEFAULT_PROFILES_FILE'] == str(REPO / 'params' / 'fastdds' /
                                                        'loopback.xml')
    ports = dds_ports_of_a_running_sim(env, ros_domain_id)
    assert ports, 'the sim node opened no DDS port of its domain'
    assert all(address == '127.0.0.1' for address, _ in ports), ports

    # The control: without the profile the same ports listen on every interface.
    without = {key: value for key, value in env.items()
               if key != 'FASTRTPS_DEFAULT_PROFILES_FILE'}
    ports = dds_ports_of_a_running_sim(without, ros_domain_id)
    assert any(address == '0.0.0.0' for address, _ in ports), ports


def test_env_sh_leaves_a_chosen_profile_alone():
    env = dict(os.environ, FASTRTPS_DEFAULT_PROFILES_FILE='/etc/lab-profile.xml')
    script = f'source {REPO / "scripts" / "env.sh"} >/dev/null 2>&1 && ' \
             'echo "$FASTRTPS_DEFAULT_PROFILES_FILE"'
    result = subprocess.run(['bash', '-c', script], cwd='/tmp', env=env, capture_output=True,
                            text=True, check=True)
    assert result.stdout.strip() == '/etc/lab-profile.xml'
