"""The study folder's session index: its file and entry format (pure, no rclpy).

Written by the session runner (``hrc_live.study.record_session``: one entry per session of a
subject, practice or condition, whose ``attempts`` list every run of it: an aborted condition
resumed later is one entry with two attempts) and read by the report by subject
(``hrc_bag.report.study``): a contract between two packages, so it lives here (hrc_bag sits
below hrc_live). The rest of the study protocol (registry, case orders) is ``hrc_live.study``;
the NASA-TLX scales are ``hrc_common.tlx``.

Indexes written before attempts existed hold a resumed session once per run, without
``attempts``: :func:`merge_attempts` reads them as one entry per session all the same.

Every read-modify-write of a study file holds :func:`study_lock` (an exclusive ``flock`` on
``.lock`` in the study folder): two sessions or ``hrc study register`` calls at the same moment
each see the other's entry instead of one replacing the other's file.
"""

import contextlib
from dataclasses import dataclass, field
import fcntl
import os
import pathlib

from hrc_common.cases import paper_case_ids

INDEX_FILE = 'index.yaml'
LOCK_FILE = '.lock'
ATTEMPT_FIELDS = ('started', 'ended', 'exit_code')
SESSION_KINDS = ('practice', 'condition')


def __getattr__(name):
    """Return ``PAPER_CASES``: the paper's cases of params/cases.yaml (``paper_case_ids``).

    Read when first asked for (not at import: a broken cases file is reported by whoever needs
    the cases, with its reasons), never a copy of the case table.
    """
    if name == 'PAPER_CASES':
        return paper_case_ids()
    raise AttributeError(f'module {__name__!r} has no attribute {name!r}')


@dataclass
class IndexEntry:
    """One session a subject took part in."""

    subject_id: str
    session_id: str
    case: int
    kind: str                   # practice | condition
    position: int               # 1-based position of the case in the subject's order (0 = ?)
    started: str                # ISO date-time
    ended: str
    exit_code: int
    bags: str                   # folder of the session's bags
    run_dir: str                # logs, parameters, checkpoints, report
    tlx_file: str = ''          # raw NASA-TLX answers ('' = none stored)
    # Every run of this session in order, {started, ended, exit_code}; started is the first's,
    # ended and exit_code the last's ([] in an entry written before attempts existed: one run).
    attempts: list = field(default_factory=list)
    # The checkpoint of the subject's earlier session this one started from (a returning
    # person; '' = a new policy). Entries written before it existed read as ''.
    start_from: str = ''


def attempt_of(record: dict) -> dict:
    """Return the one attempt a record without ``attempts`` stands for."""
    return {name: record.get(name) for name in ATTEMPT_FIELDS}


def add_attempt(record: dict, attempt: dict) -> dict:
    """Fold ``attempt`` (a later run of the same session) into ``record`` (an entry mapping).

    The entry keeps its first start and takes the new end and exit code; the TLX file stays
    named once any run stored the answers. ``record`` is changed and returned.
    """
    attempts = list(record.get('attempts') or [attempt_of(record)])
    attempts.append({name: attempt[name] for name in ATTEMPT_FIELDS})
    record['attempts'] = attempts
    record['started'] = attempts[0]['started']
    record['ended'], record['exit_code'] = attempts[-1]['ended'], attempts[-1]['exit_code']
    record['tlx_file'] = attempt.get('tlx_file') or record.get('tlx_file', '')
    return record


def merge_attempts(records: list) -> list:
    """Return ``records`` with one mapping per (session id, kind), runs folded into attempts.

    For indexes written before attempts existed, where a resumed session appears once per run;
    records are mappings already checked by shape, in the file's order.
    """
    merged = {}
    for record in records:
        key = (record.get('session_id'), record.get('kind'))
        if key in merged:
            add_attempt(merged[key], record)
        else:
            merged[key] = dict(record)
    for record in merged.values():
        record.setdefault('attempts', [attempt_of(record)])
        if not record['attempts']:
            record['attempts'] = [attempt_of(record)]
    return list(merged.values())


@contextlib.contextmanager
def study_lock(folder):
    """Hold the study folder's exclusive lock (blocking) for one read-modify-write.

    ``flock`` on a lock file rather than the data file: the data file is replaced atomically
    (a new inode), so a lock on it would not be seen by the next writer. Released when the
    process ends, so a killed writer never leaves it held.
    """
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    descriptor = os.open(folder / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o600)
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX)
        yield
    finally:
        os.close(descriptor)
