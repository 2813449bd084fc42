"""Start node processes and supervise them (pure Python, no rclpy).

Each node runs in its own process group, started exactly as ``ros2 run`` would
(``<prefix>/lib/<pkg>/<exe>``), with its output written to ``<log_dir>/<name>.log``. Children get
``PR_SET_PDEATHSIG`` so that even a SIGKILLed supervisor leaves no orphan behind. Logs may
quote the subject id or notes (a live session), so they are owner-only (0600).
"""

import ctypes
from dataclasses import dataclass, field
import os
import pathlib
import signal
import subprocess
import time

from hrc_common.contract import PERSONAL_FILE_MODE

PR_SET_PDEATHSIG = 1


def _die_with_parent():
    """Ask the kernel to SIGTERM this child when its parent dies (Linux)."""
    try:
        ctypes.CDLL('libc.so.6', use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    except OSError:
        pass


def _child_setup(niceness: int):
    """Return the function run in the child before exec: parent-death signal, niceness."""
    def setup():
        _die_with_parent()
        if niceness:
            os.nice(niceness)
    return setup


def describe_exit(returncode: int) -> str:
    """Return a readable description of a process exit code."""
    if returncode is None:
        return 'still running'
    if returncode < 0:
        try:
            return f'killed by {signal.Signals(-returncode).name}'
        except ValueError:
            return f'killed by signal {-returncode}'
    return f'exit code {returncode}'


@dataclass
class ManagedProcess:
    """One supervised node process."""

    name: str
    command: list
    log_path: pathlib.Path
    popen: subprocess.Popen
    started: float = field(default_factory=time.monotonic)

    @property
    def returncode(self):
        """Return the exit code, or None while running."""
        return self.popen.poll()

    def tail(self, lines: int = 15) -> str:
        """Return the last lines the process printed."""
        try:
            text = self.log_path.read_text(errors='replace')
        except OSError:
            return ''
        return '\n'.join(text.splitlines()[-lines:])


class Supervisor:
    """Starts node processes, notices exits, and stops them all in a chosen order."""

    def __init__(self, log_dir, env=None):
        self.log_dir = pathlib.Path(log_dir)
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.env = dict(os.environ if env is None else env)
        self.processes = {}

    def start(self, name: str, command: list, niceness: int = 0) -> ManagedProcess:
        """Start ``command`` as the process called ``name`` (``niceness`` > 0: lower priority)."""
        log_path = self.log_dir / f'{name}.log'
        descriptor = os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, PERSONAL_FILE_MODE)
        os.fchmod(descriptor, PERSONAL_FILE_MODE)   # also when the file existed
        with os.fdopen(descriptor, 'wb') as log:
            popen = subprocess.Popen(command, env=self.env, stdout=log,
                                     stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                     start_new_session=True, preexec_fn=_child_setup(niceness))
        process = ManagedProcess(name, list(command), log_path, popen)
        self.processes[name] = process
        return process

    def exited(self) -> list:
        """Return the processes that have exited, in start order."""
        return [process for process in self.processes.values()
                if process.returncode is not None]

    def running(self) -> list:
        """Return the names of the processes still running."""
        return [name for name, process in self.processes.items() if process.returncode is None]

    def stop(self, name: str, timeout: float = 10.0) -> int:
        """SIGINT one process (as Ctrl-C), SIGTERM then SIGKILL its group if it hangs."""
        process = self.processes[name]
        for sig, wait in ((signal.SIGINT, timeout), (signal.SIGTERM, timeout / 2),
                          (signal.SIGKILL, timeout)):
            if process.returncode is not None:
                break
            try:
                if sig == signal.SIGKILL:
                    os.killpg(process.popen.pid, sig)
                else:
                    process.popen.send_signal(sig)
            except ProcessLookupError:
                break
            try:
                process.popen.wait(timeout=wait)
            except subprocess.TimeoutExpired:
                continue
        return process.popen.wait()

    def stop_all(self, order=(), timeout: float = 10.0) -> dict:
        """Stop every running process: first those in ``order``, then the rest.

        Returns {name: returncode}. Stopping in order lets the recorder go last and close its
        bags after every publisher has stopped.
        """
        names = [name for name in order if name in self.processes]
        names += [name for name in self.processes if name not in names]
        return {name: self.stop(name, timeout) for name in names}
