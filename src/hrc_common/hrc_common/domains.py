"""ROS domain ids reserved machine-wide with lock files (tests, experiment workers).

Two processes that hold different reservations never share a ROS_DOMAIN_ID, so concurrent test
runs and parallel sessions on one machine never see each other's nodes.
"""

import fcntl
import itertools
import os

# Test domain ids: 1..100 (Fast DDS ports stay valid up to 232; the session benchmarks and the
# experiment runner use 40+ and 90+ only when they are not under test). Each test reserves one
# with an exclusive lock file, so concurrent test runs on one machine never share a domain.
DOMAIN_IDS = range(1, 101)
_NEXT = itertools.count(os.getpid())
LOCK_DIR = os.environ.get('HRC_DOMAIN_LOCK_DIR', '/tmp')


class DomainReservation:
    """A ROS domain id held by this process until :meth:`release` (a lock file)."""

    def __init__(self, attempts: int = 3 * len(DOMAIN_IDS)):
        for _ in range(attempts):
            candidate = DOMAIN_IDS[next(_NEXT) % len(DOMAIN_IDS)]
            path = os.path.join(LOCK_DIR, f'hrc-ros-domain-{candidate}.lock')
            handle = open(path, 'a')
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                handle.close()
                continue
            self.domain_id, self._handle = candidate, handle
            return
        raise RuntimeError(f'no free ROS domain id in {DOMAIN_IDS}: too many concurrent '
                           'tests or sessions')

    def release(self) -> None:
        """Give the domain id back."""
        self._handle.close()


class DomainTaken(RuntimeError):
    """Another hrc session runs on this ROS domain on this machine (the message says which)."""


class SessionOnDomain:
    """The mark of a session running on a ROS domain of this machine (a lock file held).

    Two sessions on one domain take each other's messages: one agent died of the other's
    states, the other filed them in its bags. The session runner holds this for its lifetime
    (another lock than :class:`DomainReservation`, which the runner's parent may hold for it);
    a second runner on the domain is refused at once, with the session that has it. The lock
    goes with the process, however it ends. Sessions on other machines of the network are not
    seen: ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` (the default of ``hrc session``) keeps
    them apart.
    """

    def __init__(self, domain_id: int, session_id: str):
        path = os.path.join(LOCK_DIR, f'hrc-session-domain-{int(domain_id)}.lock')
        handle = open(path, 'a+')
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.seek(0)
            holder = handle.read().strip() or 'an hrc session'
            handle.close()
            raise DomainTaken(f'ROS_DOMAIN_ID {domain_id} is in use by {holder} on this '
                              "machine: its nodes would take this session's messages; give "
                              '--domain-id with another id (0..101)') from None
        handle.seek(0)
        handle.truncate()
        handle.write(f'session {session_id} (pid {os.getpid()})\n')
        handle.flush()
        self.domain_id, self._handle = domain_id, handle

    def release(self) -> None:
        """Give the domain back (the process's end does too)."""
        self._handle.close()
