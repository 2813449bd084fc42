"""Helpers for tests of whole sessions: a task tree every state meets, exact digests, a runner."""

import os
import pathlib
import signal
import subprocess

import yaml

from hrc_common.executables import executable_path
from hrc_common.paths import params_dir


def easy_task_tree(folder) -> str:
    """Write the task tree of params/ with every tolerance 100 into ``folder``; return its path.

    Any state meets such a tree, so each training step converges as soon as the judging rule
    allows: a short session that still passes through every step of its strategy.
    """
    def widen(node):
        if isinstance(node, dict):
            return {key: 100.0 if key == 'tolerance' else widen(item)
                    for key, item in node.items()}
        if isinstance(node, list):
            return [widen(item) for item in node]
        return node

    tree = yaml.safe_load((params_dir() / 'task_tree.yaml').read_text())
    path = pathlib.Path(folder) / 'easy_tree.yaml'
    path.write_text(yaml.safe_dump(widen(tree)))
    return str(path)


def exact_plain(value):
    """Return a message (or any value) as JSON-able plain values, floats as their repr.

    For digests of sessions that must repeat bit for bit: ``repr`` keeps every bit of a float.
    """
    if isinstance(value, dict):
        return {key: exact_plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [exact_plain(item) for item in value]
    if isinstance(value, bool) or value is None or isinstance(value, (int, str)):
        return value
    if isinstance(value, float):
        return repr(value)
    if hasattr(value, '__dict__'):
        return exact_plain(vars(value))
    return repr(float(value))


class SessionRunner:
    """One ``hrc session`` of a test in ``folder`` (bags/, runs/), its terminal in a file.

    For the tests that act on a running session's nodes (stop one, watch its log): the
    runner's output, a node's log (``runs/<id>/logs/<node>.log``), and a stop that takes the
    runner's process group down when the test ends early.
    """

    def __init__(self, folder, domain_id: int, session_id: str, *options):
        self.folder, self.session_id = pathlib.Path(folder), session_id
        self.log = open(self.folder / 'runner.log', 'w+')
        self.process = subprocess.Popen(
            [str(executable_path('hrc_bringup', 'hrc')), 'session', '--domain-id',
             str(domain_id), '--session-id', session_id, '--bags-dir', 'bags', '--runs-dir',
             'runs', *options],
            cwd=self.folder, stdout=self.log, stderr=subprocess.STDOUT, text=True,
            start_new_session=True)

    def output(self) -> str:
        """Everything the runner printed so far."""
        self.log.seek(0)
        return self.log.read()

    def node_log(self, node: str) -> str:
        """Return what ``node`` logged so far ('' before its log exists)."""
        path = self.folder / 'runs' / self.session_id / 'logs' / f'{node}.log'
        return path.read_text() if path.exists() else ''

    def bags(self) -> pathlib.Path:
        """Return the session's bag folder."""
        return self.folder / 'bags' / self.session_id

    def stop(self) -> None:
        """Kill the runner's process group if it still runs (a test that failed early)."""
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()
