"""The study protocol (pure): subject registry, counterbalanced case order, per-subject index.

A study lives in one folder (``--study-dir``, default ``study``):

* ``subjects.yaml``: the pseudonymous registry: per subject its id (the pseudonym, e.g.
  ``P07``: letters, digits, ``_ . -``), consent ``yes``/``no`` and the date it was recorded,
  the registration date and, once assigned, its case order. No names: the registry takes no
  other fields (a name, e-mail or birth date cannot be stored by mistake); the key that links a
  pseudonym to a person stays on paper, outside this software.
* ``index.yaml``: one entry per session a subject took part in (practice or condition): the
  session id, case, kind, position in the subject's order, start and end, exit code, every
  attempt (an aborted session resumed later is one entry with two), and the files of the
  session (bags, run folder, NASA-TLX once stored), so a report can tabulate by subject.

Both files hold subject ids, so they are written with mode 0600 (owner only), atomically, and
every change is a read-modify-write under the study folder's lock
(``hrc_common.study_index.study_lock``): concurrent registrations or sessions all keep theirs.

Counterbalancing (a modelling choice; Williams 1949, "Experimental designs balanced for the
estimation of residual effects of treatments", Aust. J. Sci. Res. A 2:149-168): for an even
number of cases one Williams square (n rows): each case once in each position and each case
directly followed by each other case exactly once; for an odd number the square and its mirror
(2n rows) give the same first-order balance. Subject k (in registration order) takes row
k mod rows.
"""

from dataclasses import asdict, dataclass, field
import datetime
import pathlib
import typing

from hrc_common import bounded_yaml
from hrc_common.contract import atomic_write, id_problem, PERSONAL_FILE_MODE
from hrc_common.session_control import FINAL_CHECKPOINT
from hrc_common.study_index import (add_attempt, attempt_of, INDEX_FILE, IndexEntry,
                                    merge_attempts, PAPER_CASES, SESSION_KINDS, study_lock)
import yaml

SUBJECTS_FILE = 'subjects.yaml'
CONSENT_VALUES = ('yes', 'no')
SUBJECT_FIELDS = ('id', 'consent', 'consent_date', 'registered', 'order')


class StudyError(ValueError):
    """A registry, order or index problem; the message lists every reason."""


@dataclass
class Subject:
    """One pseudonymous subject of the registry."""

    id: str
    consent: str                # 'yes' or 'no'
    consent_date: str           # ISO date the consent answer was recorded
    registered: str             # ISO date of registration
    order: list = field(default_factory=list)   # the subject's cases in order ([] = none yet)


def _date_problem(text, what: str) -> str:
    try:
        datetime.date.fromisoformat(str(text))
    except ValueError:
        return f'{what} {text!r} is not a date (YYYY-MM-DD)'
    return ''


def subject_problems(record) -> list:
    """Return every reason why ``record`` (a mapping) is not a valid registry entry."""
    if not isinstance(record, dict):
        return [f'entry {record!r} is not a mapping']
    reasons = []
    extra = sorted(set(record) - set(SUBJECT_FIELDS))
    if extra:
        reasons.append(f'fields {extra} are not allowed (the registry holds no names or other '
                       f'personal data: only {list(SUBJECT_FIELDS)})')
    problem = id_problem(record.get('id'), 'subject id')
    if problem:
        reasons.append(problem)
    if record.get('consent') not in CONSENT_VALUES:
        reasons.append(f"consent must be 'yes' or 'no', got {record.get('consent')!r}")
    for name in ('consent_date', 'registered'):
        problem = _date_problem(record.get(name), name)
        if problem:
            reasons.append(problem)
    order = record.get('order', [])
    if not isinstance(order, list) or any(case not in PAPER_CASES for case in order) \
            or len(set(order)) != len(order):
        reasons.append(f'order must list distinct paper cases 1..6, got {order!r}')
    return [f'subject {record.get("id")!r}: {reason}' for reason in reasons]


def _study_file(path: pathlib.Path):
    """Return the YAML document of a study file ([] when empty); StudyError if unreadable."""
    try:
        return bounded_yaml.load_file(path) or []
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as error:
        raise StudyError(f'{path}: not readable as YAML ({bounded_yaml.describe(error)})') \
            from None


def load_registry(folder) -> list:
    """Return the Subjects of ``folder``/subjects.yaml ([] if there is none); check every entry."""
    path = pathlib.Path(folder) / SUBJECTS_FILE
    if not path.is_file():
        return []
    document = _study_file(path)
    if not isinstance(document, list):
        raise StudyError(f'{path}: not a list of subjects')
    reasons = [reason for record in document for reason in subject_problems(record)]
    ids = [record.get('id') for record in document if isinstance(record, dict)]
    reasons += [f'subject {id_!r} is registered twice' for id_ in sorted(set(ids))
                if ids.count(id_) > 1]
    if reasons:
        raise StudyError(f'{path}: ' + '; '.join(reasons))
    return [Subject(**{'order': [], **record}) for record in document]


def save_registry(folder, subjects: list) -> pathlib.Path:
    """Write the registry (0600, atomically)."""
    path = pathlib.Path(folder) / SUBJECTS_FILE
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, yaml.safe_dump([asdict(subject) for subject in subjects],
                                      sort_keys=False), mode=PERSONAL_FILE_MODE)
    return path


def update_registry(folder, change) -> tuple:
    """Apply ``change(subjects)`` to the registry under the study lock; return (result, path).

    The registry is read, changed and written while the lock is held, so two registrations at
    the same moment both stay (without it each wrote the list it had read, one replacing the
    other's). Nothing is written when ``change`` raises.
    """
    with study_lock(folder):
        subjects = load_registry(folder)
        result = change(subjects)
        return result, save_registry(folder, subjects)


def register(subjects: list, subject_id: str, consent: str, date: str,
             today: str = None) -> Subject:
    """Add a subject or record a new consent answer; return the entry (raise StudyError)."""
    today = today or datetime.date.today().isoformat()
    record = {'id': subject_id, 'consent': consent, 'consent_date': date, 'registered': today}
    existing = next((subject for subject in subjects if subject.id == subject_id), None)
    if existing is not None:
        record['registered'], record['order'] = existing.registered, existing.order
    reasons = subject_problems(record)
    if reasons:
        raise StudyError('; '.join(reasons))
    if existing is not None:
        existing.consent, existing.consent_date = consent, date
        return existing
    subject = Subject(**record)
    subjects.append(subject)
    return subject


def consent_problem(subjects: list, subject_id: str) -> str:
    """Return why ``subject_id`` may not take part now ('' = registered with consent yes)."""
    subject = next((subject for subject in subjects if subject.id == subject_id), None)
    if subject is None:
        return (f'subject {subject_id!r} is not in the registry: register them first '
                f'(study register {subject_id} --consent yes)')
    if subject.consent != 'yes':
        return (f'subject {subject_id!r} has consent {subject.consent!r} (recorded '
                f'{subject.consent_date}): no session without consent')
    return ''


# ---------------------------------------------------------------------------- counterbalancing

def williams_rows(count: int) -> list:
    """Return the rows of a Williams design over ``count`` items (indices 0..count-1).

    Even ``count``: one square (count rows); odd: the square and its mirror (2*count rows).
    """
    if count < 1:
        raise StudyError('at least one case is needed')
    # First row: 0, 1, n-1, 2, n-2, ... ; row r adds r to every entry (mod n).
    first, low, high = [0], 1, count - 1
    while len(first) < count:
        first.append(low)
        low += 1
        if len(first) < count:
            first.append(high)
            high -= 1
    rows = [[(item + shift) % count for item in first] for shift in range(count)]
    if count % 2 == 1:
        rows += [list(reversed(row)) for row in rows]
    return rows


def case_orders(cases: typing.Sequence[int]) -> list:
    """Return the counterbalanced orders of ``cases`` (the researcher's set, default 1..6)."""
    cases = list(cases)
    problems = [case for case in cases if case not in PAPER_CASES]
    if problems or len(set(cases)) != len(cases) or not cases:
        raise StudyError(f'cases must be distinct paper cases 1..6, got {cases}')
    return [[cases[index] for index in row] for row in williams_rows(len(cases))]


def assign_orders(subjects: list, cases: typing.Sequence[int] = PAPER_CASES) -> list:
    """Give every consenting subject without an order the next row; return those assigned.

    Rows go by position among the subjects with an order (registration order), so a subject
    added later continues the rotation and earlier assignments never change.
    """
    orders = case_orders(cases)
    assigned = []
    taken = sum(1 for subject in subjects if subject.order)
    for subject in subjects:
        if subject.order or subject.consent != 'yes':
            continue
        subject.order = orders[taken % len(orders)]
        taken += 1
        assigned.append(subject)
    return assigned


# ---------------------------------------------------------------------------- session index

def _index_records(folder) -> list:
    path = pathlib.Path(folder) / INDEX_FILE
    if not path.is_file():
        return []
    document = _study_file(path)
    if not isinstance(document, list) or not all(isinstance(item, dict) for item in document):
        raise StudyError(f'{path}: not a list of session entries')
    return merge_attempts(document)


def load_index(folder) -> list:
    """Return the IndexEntries of ``folder``/index.yaml ([] if none), one per session."""
    try:
        return [IndexEntry(**record) for record in _index_records(folder)]
    except TypeError as error:
        raise StudyError(f'{pathlib.Path(folder) / INDEX_FILE}: an entry does not fit: '
                         f'{error}') from None


def record_session(folder, entry: IndexEntry) -> pathlib.Path:
    """Add a run of a session to the index (0600, atomically, under the study lock).

    A session already indexed (the same id and kind: a resume of an aborted condition) gets the
    run as its next attempt; any other gets a new entry.
    """
    if entry.kind not in SESSION_KINDS:
        raise StudyError(f'kind must be one of {SESSION_KINDS}, got {entry.kind!r}')
    path = pathlib.Path(folder) / INDEX_FILE
    with study_lock(folder):
        records = _index_records(folder)
        new = asdict(entry)
        same = next((record for record in records if (record['session_id'], record['kind'])
                     == (entry.session_id, entry.kind)), None)
        if same is None:
            new['attempts'] = new['attempts'] or [attempt_of(new)]
            records.append(new)
        else:
            add_attempt(same, new)
        atomic_write(path, yaml.safe_dump(records, sort_keys=False), mode=PERSONAL_FILE_MODE)
    return path


def position_of(subjects: list, subject_id: str, case: int) -> int:
    """Return the 1-based position of ``case`` in the subject's order (0 if not in it)."""
    subject = next((subject for subject in subjects if subject.id == subject_id), None)
    if subject is None or case not in subject.order:
        return 0
    return subject.order.index(case) + 1


def by_subject(entries: list) -> dict:
    """Return {subject id: [entries in order of start]}."""
    table = {}
    for entry in sorted(entries, key=lambda item: item.started):
        table.setdefault(entry.subject_id, []).append(entry)
    return table


def returning_start(entries: list, subject_id: str, case: int):
    """Return (session id, checkpoint) a returning subject's session of ``case`` starts from.

    The subject's latest condition of that case that ran to its end (exit 0) and left its
    final checkpoint (``<runs dir>/checkpoints/<session id>/final.pt``, the session runner's
    layout): the robot starts from what it learned with this person. None: no such session.
    """
    finished = [entry for entry in entries if entry.subject_id == subject_id
                and entry.case == case and entry.kind == 'condition' and entry.exit_code == 0]
    for entry in sorted(finished, key=lambda item: item.ended, reverse=True):
        checkpoint = (pathlib.Path(entry.run_dir).parent / 'checkpoints' / entry.session_id
                      / FINAL_CHECKPOINT)
        if checkpoint.is_file():
            return entry.session_id, checkpoint
    return None


def order_warning(subjects: list, entries: list, subject_id: str, case: int) -> str:
    """Return why running ``case`` now breaks the subject's registered order ('' if it does not).

    The order counterbalances learning effects across subjects (a Williams square): a
    condition run before the ones ahead of it in the order, or one run again after it ended
    well (exit 0), changes what the study measures.
    """
    subject = next((subject for subject in subjects if subject.id == subject_id), None)
    if subject is None or not subject.order:
        return f'{subject_id} has no case order in the registry (run "hrc study assign")'
    if case not in subject.order:
        return f'case {case} is not in the order of {subject_id} {subject.order}'
    done = {entry.case for entry in entries if entry.subject_id == subject_id
            and entry.kind == 'condition' and entry.exit_code == 0}
    position = subject.order.index(case) + 1
    if case in done:
        return (f'case {case} (condition {position} of {subject_id}) was run to its end '
                'already: this run is a repeat')
    ahead = [earlier for earlier in subject.order[:position - 1] if earlier not in done]
    if ahead:
        return (f'case {case} is condition {position} of {subject_id} (order {subject.order}) '
                f'but {", ".join(f"case {earlier}" for earlier in ahead)} before it '
                f'{"has" if len(ahead) == 1 else "have"} not run to the end: out of the '
                'registered order')
    return ''
