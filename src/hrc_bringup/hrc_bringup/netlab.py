"""Two hosts on one machine: network namespaces joined by an emulated link.

A lab runs the person's station (joystick, display) and the trainer (sim, agent, recorder) on two
computers. To test that layout here, :class:`TwoHostLab` makes two Linux network namespaces,
``<name>-station`` and ``<name>-trainer``, and joins them by a point-to-point IPv4 link whose
delay, jitter, loss and outages it controls. Processes are started inside a namespace with
``ip netns exec`` (:meth:`TwoHostLab.command`).

Why the link is emulated in user space: the usual tool, ``tc qdisc ... netem``, needs the
kernel's ``sch_netem`` module, which this machine's kernel does not have ("Specified qdisc kind is
unknown"). Each namespace therefore gets a TUN device, and one thread of this process
(:class:`LinkEmulator`) carries every IP packet from one TUN device to the other, holding it for
``delay`` plus a uniform jitter, dropping it with probability ``loss`` (seeded), and dropping
everything during an outage. The emulator keeps each direction in order (like a real Wi-Fi
link, unlike netem with jitter, which reorders). Its own cost is one ``select`` + ``read`` +
``write`` per packet in Python: about 20-50 us, well under the 2 ms of the best link emulated.

Needs root (``ip netns``, ``/dev/net/tun``). Addresses: 10.231.<k>.1 (station) and
10.231.<k>.2 (trainer) exist only inside the two namespaces this class made; nothing outside
them is ever addressed. Pure Python, no rclpy.
"""

import dataclasses
import fcntl
import heapq
import os
import random
import selectors
import shutil
import struct
import subprocess
import threading
import time

TUNSETIFF = 0x400454CA
IFF_TUN = 0x0001
IFF_NO_PI = 0x1000
MTU = 1500


@dataclasses.dataclass(frozen=True)
class LinkProfile:
    """The quality of the link between the two hosts, applied in both directions."""

    delay: float = 0.0
    """One-way delay added to every packet (s)."""
    jitter: float = 0.0
    """Half-width of the uniform random variation of the delay (s); order is kept."""
    loss: float = 0.0
    """Probability that a packet is dropped, in [0, 1)."""

    def describe(self) -> str:
        """Return e.g. '30 ms +- 10 ms, 1.0% loss'."""
        return (f'{self.delay * 1e3:g} ms +- {self.jitter * 1e3:g} ms, '
                f'{self.loss * 100:.1f}% loss')


# The links the two-host test and the README talk about.
LOCAL = LinkProfile()
WIRED_LAB = LinkProfile(delay=0.002)
POOR_WIFI = LinkProfile(delay=0.030, jitter=0.010, loss=0.01)


def _run(*args: str) -> None:
    result = subprocess.run(args, capture_output=True, text=True)
    if result.returncode != 0:
        raise NetlabError(f"'{' '.join(args)}' failed: {result.stderr.strip()}")


class NetlabError(RuntimeError):
    """The namespaces or the link could not be made (with the reason)."""


def check_possible() -> list:
    """Return every reason why a lab cannot be made here (empty when it can)."""
    reasons = []
    if os.geteuid() != 0:
        reasons.append('network namespaces need root (run as root)')
    if shutil.which('ip') is None:
        reasons.append("the 'ip' command is missing (Debian: apt-get install iproute2)")
    if not os.path.exists('/dev/net/tun'):
        reasons.append('/dev/net/tun is missing (no TUN support in this kernel)')
    return reasons


def open_tun(name: str) -> int:
    """Create TUN device ``name`` (IP packets, no extra header); return its file descriptor."""
    fd = os.open('/dev/net/tun', os.O_RDWR | os.O_NONBLOCK)
    try:
        fcntl.ioctl(fd, TUNSETIFF, struct.pack('16sH', name.encode(), IFF_TUN | IFF_NO_PI))
    except OSError as error:
        os.close(fd)
        raise NetlabError(f'cannot create TUN device {name}: {error}') from error
    return fd


class LinkEmulator:
    """Carry packets between two TUN file descriptors with delay, jitter, loss and outages."""

    def __init__(self, fd_a: int, fd_b: int, profile: LinkProfile, seed: int = 0):
        self.fds = (fd_a, fd_b)
        self.profile = profile
        self.random = random.Random(seed)
        self.down_until = 0.0
        self.counts = {'carried': 0, 'lost': 0, 'dropped_down': 0, 'overflow': 0}
        self._queue = []        # (due time, sequence, destination fd, packet)
        self._last_due = {fd_a: 0.0, fd_b: 0.0}
        self._sequence = 0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name='netlab-link', daemon=True)

    def start(self):
        """Start carrying packets (a daemon thread)."""
        self._thread.start()

    def stop(self):
        """Stop carrying packets; queued ones are dropped."""
        self._stop.set()
        self._thread.join(timeout=2.0)

    def set_profile(self, profile: LinkProfile):
        """Change the link quality from now on."""
        with self._lock:
            self.profile = profile

    def outage(self, seconds: float):
        """Drop every packet in both directions for ``seconds`` from now (a cable pulled)."""
        with self._lock:
            self.down_until = time.monotonic() + seconds

    def _accept(self, source: int, packet: bytes, now: float):
        destination = self.fds[1] if source == self.fds[0] else self.fds[0]
        with self._lock:
            profile = self.profile
            if now < self.down_until:
                self.counts['dropped_down'] += 1
                return
            if profile.loss > 0.0 and self.random.random() < profile.loss:
                self.counts['lost'] += 1
                return
            delay = profile.delay + (self.random.uniform(-profile.jitter, profile.jitter)
                                     if profile.jitter > 0.0 else 0.0)
            # Keep order per direction: never due before the packet sent before it.
            due = max(now + max(delay, 0.0), self._last_due[destination])
            self._last_due[destination] = due
            self._sequence += 1
            heapq.heappush(self._queue, (due, self._sequence, destination, packet))

    def _deliver_due(self, now: float):
        while self._queue and self._queue[0][0] <= now:
            _, _, destination, packet = heapq.heappop(self._queue)
            try:
                os.write(destination, packet)
                self.counts['carried'] += 1
            except OSError:     # the receiving device's queue is full
                self.counts['overflow'] += 1

    def _loop(self):
        selector = selectors.DefaultSelector()
        for fd in self.fds:
            selector.register(fd, selectors.EVENT_READ)
        while not self._stop.is_set():
            now = time.monotonic()
            self._deliver_due(now)
            timeout = 0.05 if not self._queue else max(0.0, self._queue[0][0] - now)
            for key, _ in selector.select(min(timeout, 0.05)):
                while True:
                    try:
                        packet = os.read(key.fd, MTU + 64)
                    except BlockingIOError:
                        break
                    except OSError:
                        break
                    self._accept(key.fd, packet, time.monotonic())
        selector.close()


class TwoHostLab:
    """Two namespaces, 'station' and 'trainer', joined by an emulated link (see module doc)."""

    def __init__(self, name: str = '', profile: LinkProfile = LOCAL, seed: int = 0,
                 subnet: int = 0):
        self.name = name or f'hrc{os.getpid() % 100000}'
        self.subnet = subnet or (os.getpid() % 200) + 20
        self.station = f'{self.name}-station'
        self.trainer = f'{self.name}-trainer'
        self.station_address = f'10.231.{self.subnet}.1'
        self.trainer_address = f'10.231.{self.subnet}.2'
        self.profile = profile
        self.seed = seed
        self.link = None
        self._fds = []

    def __enter__(self):
        reasons = check_possible()
        if reasons:
            raise NetlabError('cannot make the two-host lab: ' + '; '.join(reasons))
        try:
            self._make()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc):
        self.close()

    def _make(self):
        devices = []
        for namespace, address, peer in ((self.station, self.station_address,
                                          self.trainer_address),
                                         (self.trainer, self.trainer_address,
                                          self.station_address)):
            _run('ip', 'netns', 'add', namespace)
            device = f'{self.name[:8]}{"s" if namespace == self.station else "t"}'
            self._fds.append(open_tun(device))
            devices.append(device)
            _run('ip', 'link', 'set', device, 'netns', namespace)
            _run('ip', '-n', namespace, 'link', 'set', 'lo', 'up')
            _run('ip', '-n', namespace, 'addr', 'add', address, 'peer', peer, 'dev', device)
            _run('ip', '-n', namespace, 'link', 'set', device, 'mtu', str(MTU), 'up')
            # DDS discovery multicast goes out on the link too (static peers make it optional).
            _run('ip', '-n', namespace, 'link', 'set', device, 'multicast', 'on')
            _run('ip', '-n', namespace, 'route', 'add', '224.0.0.0/4', 'dev', device)
        self.link = LinkEmulator(self._fds[0], self._fds[1], self.profile, self.seed)
        self.link.start()

    def close(self):
        """Stop the link and delete both namespaces (their devices go with them)."""
        if self.link is not None:
            self.link.stop()
            self.link = None
        for fd in self._fds:
            try:
                os.close(fd)
            except OSError:
                pass
        self._fds = []
        for namespace in (self.station, self.trainer):
            subprocess.run(['ip', 'netns', 'del', namespace], capture_output=True)

    def command(self, host: str, argv: list) -> list:
        """Return ``argv`` wrapped to run inside ``host`` ('station' or 'trainer')."""
        namespace = {'station': self.station, 'trainer': self.trainer}[host]
        return ['ip', 'netns', 'exec', namespace, *argv]

    def ros_environment(self, host: str, domain_id: int) -> dict:
        """Return the ROS 2 discovery settings of ``host``: static peer = the other host.

        Automatic discovery stays on this host (LOCALHOST) and the other host is a static peer
        (unicast discovery, no multicast on the lab network;
        the layout docs/two_hosts.md recommends for a lab); Fast DDS uses UDPv4 only, since
        its shared-memory transport would bypass the network between namespaces of one machine.
        """
        peer = self.trainer_address if host == 'station' else self.station_address
        return {'ROS_DOMAIN_ID': str(domain_id), 'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST',
                'ROS_STATIC_PEERS': peer, 'FASTDDS_BUILTIN_TRANSPORTS': 'UDPv4'}
