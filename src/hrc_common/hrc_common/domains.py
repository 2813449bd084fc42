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
