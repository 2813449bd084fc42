"""Helpers for tests of whole sessions: a task tree every state meets, exact digests."""

import pathlib

import yaml

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
