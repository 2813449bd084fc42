"""The emulated link of the two-host lab: delay, order, loss and outages, on datagram sockets.

The emulator only needs file descriptors that keep packet boundaries, so a pair of Unix
datagram socket pairs stands in for the two TUN devices here; the real namespaces and TUN
devices are exercised by test/test_two_hosts.py.
"""

import socket
import time

from hrc_bringup.netlab import LinkEmulator, LinkProfile
import pytest


@pytest.fixture
def link_ends():
    """Return (station end, trainer end, emulator factory): sockets that talk over the link."""
    station, station_tun = socket.socketpair(socket.AF_UNIX, socket.SOCK_DGRAM)
    trainer, trainer_tun = socket.socketpair(socket.AF_UNIX, socket.SOCK_DGRAM)
    for end in (station_tun, trainer_tun):
        end.setblocking(False)
    emulators = []

    def make(profile, seed=0):
        emulator = LinkEmulator(station_tun.fileno(), trainer_tun.fileno(), profile, seed)
        emulator.start()
        emulators.append(emulator)
        return emulator

    yield station, trainer, make
    for emulator in emulators:
        emulator.stop()
    for end in (station, station_tun, trainer, trainer_tun):
        end.close()


def receive_all(sock, count, timeout, accounted=None):
    """Return (packets, arrival times) of up to ``count`` packets within ``timeout`` s.

    ``accounted(received)``, if given, stops the wait early once it returns True (e.g. every
    packet sent is either received or counted lost by the emulator).
    """
    sock.settimeout(0.05)
    packets, times = [], []
    deadline = time.monotonic() + timeout
    while len(packets) < count and time.monotonic() < deadline:
        if accounted is not None and accounted(len(packets)):
            break
        try:
            packets.append(sock.recv(2048))
            times.append(time.monotonic())
        except socket.timeout:
            pass
    return packets, times


def test_delay_is_added_and_order_kept_under_jitter(link_ends):
    station, trainer, make = link_ends
    make(LinkProfile(delay=0.040, jitter=0.020))
    sent = {}
    for index in range(30):
        payload = b'%03d' % index
        sent[payload] = time.monotonic()
        station.send(payload)
    packets, times = receive_all(trainer, 30, timeout=30.0)
    assert packets == [b'%03d' % index for index in range(30)]   # all, in order
    latencies = [arrival - sent[packet] for packet, arrival in zip(packets, times)]
    # Never earlier than delay - jitter (20 ms); the median above it. (The upper bound only
    # catches a delay wrong by an order of magnitude: a busy machine adds its own.)
    assert min(latencies) >= 0.019, latencies
    assert 0.025 < sorted(latencies)[15] < 1.0, latencies


def test_loss_is_seeded_and_near_the_probability(link_ends):
    station, trainer, make = link_ends
    emulator = make(LinkProfile(loss=0.2), seed=3)
    packets = []
    for batch in range(10):
        for index in range(50):
            station.send(b'%04d' % (batch * 50 + index))
        time.sleep(0.05)
        # Wait until each packet of the batch arrived or was counted lost (not a fixed 0.3 s).
        packets += receive_all(trainer, 50, timeout=30.0, accounted=lambda received, sent=(
            batch + 1) * 50, before=len(packets): (
                before + received + emulator.counts['lost'] >= sent))[0]
    lost = emulator.counts['lost']
    assert emulator.counts['overflow'] == 0
    assert lost + len(packets) == 500
    assert 60 <= lost <= 140, lost   # 100 expected; binomial sd ~9


def test_an_outage_drops_both_directions_then_the_link_returns(link_ends):
    station, trainer, make = link_ends
    emulator = make(LinkProfile())
    # An outage longer than any test, ended by hand: the emulator's thread may see the packets
    # late on a busy machine, and they must still fall inside it.
    emulator.outage(600.0)
    station.send(b'during')
    trainer.send(b'during')
    assert receive_all(trainer, 1, timeout=30.0,
                       accounted=lambda received: emulator.counts['dropped_down'] == 2)[0] == []
    assert receive_all(station, 1, timeout=0.1)[0] == []
    assert emulator.counts['dropped_down'] == 2
    emulator.outage(0.0)                  # the cable is back
    station.send(b'after')
    assert receive_all(trainer, 1, timeout=30.0)[0] == [b'after']


def test_profile_describes_itself():
    assert LinkProfile(0.03, 0.01, 0.01).describe() == '30 ms +- 10 ms, 1.0% loss'
