"""The report by subject: a live study's per-subject index read with its bags (pure, no rclpy).

A study folder (``session --study-dir DIR``, see docs/live_study.md) holds ``index.yaml``:
one entry per session a subject took part in, practice or condition, written by
``hrc_live.study.record_session``. Its format (the fields of
``hrc_common.study_index.IndexEntry``)::

    - subject_id: P01            # the pseudonym (no names anywhere)
      session_id: p01-case2      # the bags are <bags>/ = bags/<session_id>
      case: 2                    # paper case 1..6
      kind: condition            # practice | condition
      position: 1                # 1-based position of the case in the subject's order (0 = ?)
      started: '2026-11-30T21:00:00'
      ended: '2026-11-30T21:40:00'
      exit_code: 0
      bags: /abs/bags/p01-case2
      run_dir: /abs/runs/p01-case2
      tlx_file: /abs/runs/p01-case2/tlx.yaml   # '' = no answers stored
      attempts:                  # every run: an aborted session resumed later has two
      - {started: '2026-11-30T21:00:00', ended: '2026-11-30T21:10:00', exit_code: 3}
      - {started: '2026-11-30T21:15:00', ended: '2026-11-30T21:40:00', exit_code: 0}

The practice of a condition is indexed as the session ``<session_id>-practice`` (kind
``practice``); the raw NASA-TLX file (written by the display node) is a YAML list of
``{session_id, case, answered, scales: {mental, physical, temporal, performance, effort,
frustration}, raw_tlx}``.

:func:`load_study_index` reads the index with ``hrc_common.study_index.IndexEntry`` (the
format both sides import; hrc_bag sits below hrc_live, docs/architecture.md) and checks it by
shape first: every reason at once in a :class:`StudyIndexError`. An index written before
attempts existed lists a resumed session once per run: its runs are read as the attempts of one
entry. :func:`subject_rows` gives one row per condition (its practice counted apart, in its own
columns, its attempts and outcome: converged, stopped at the cap, aborted) and one per practice
without a condition.
Only pseudonymous ids, numbers and the TLX scores go into the rows: no notes, no names.
"""

import datetime
import math
import pathlib

from hrc_common import bounded_yaml
from hrc_common.contract import id_problem
from hrc_common.session_control import EXIT_OPERATOR_ABORT
from hrc_common.study_index import (ATTEMPT_FIELDS, INDEX_FILE, IndexEntry, merge_attempts,
                                    PAPER_CASES, SESSION_KINDS)
from hrc_common.tlx import check_tlx, raw_tlx
import yaml

from hrc_bag import bag_reader
from hrc_bag.format import source_names
from hrc_bag.report.loading import load_session
from hrc_bag.report.metrics import human_time
from hrc_bag.report.records import ERROR_KEYS, measures, record_from_bag_session

PRACTICE_SUFFIX = '-practice'


class StudyIndexError(ValueError):
    """The study index or a TLX file it names is not usable; the message lists every reason."""


class StudyFolderError(StudyIndexError):
    """The study folder or its index does not exist (a bad --study-dir)."""


def _text_problem(value, name: str) -> str:
    if isinstance(value, (datetime.date, datetime.datetime)):   # an unquoted YAML timestamp
        return ''
    return '' if isinstance(value, str) else f'{name} must be text, got {value!r}'


def _integer_problem(value, name: str, allowed=None) -> str:
    if isinstance(value, bool) or not isinstance(value, int):
        return f'{name} must be an integer, got {value!r}'
    if allowed is not None and value not in allowed:
        return f'{name} must be one of {list(allowed)}, got {value}'
    return ''


def entry_problems(record, number: int, fields: tuple, kinds: tuple, cases: tuple) -> list:
    """Return every reason why ``record`` (entry ``number``, 1-based) is not an index entry."""
    if not isinstance(record, dict):
        return [f'entry {number}: not a mapping ({record!r})']
    reasons = []
    required = [name for name in fields if name not in ('tlx_file', 'attempts')]
    missing = [name for name in required if name not in record]
    if missing:
        reasons.append(f'missing fields {missing}')
    extra = sorted(str(name) for name in set(record) - set(fields))
    if extra:
        reasons.append(f'unknown fields {extra}')
    for name in ('subject_id', 'session_id'):
        if name in record:
            problem = id_problem(record[name], name)
            if problem:
                reasons.append(problem)
    if 'case' in record:
        reasons.append(_integer_problem(record['case'], 'case', cases))
    if 'kind' in record and record['kind'] not in kinds:
        reasons.append(f'kind must be one of {list(kinds)}, got {record["kind"]!r}')
    if 'position' in record:
        reasons.append(_integer_problem(record['position'], 'position', range(0, 7)))
    if 'exit_code' in record:
        reasons.append(_integer_problem(record['exit_code'], 'exit_code'))
    for name in ('started', 'ended', 'bags', 'run_dir', 'tlx_file'):
        if name in record:
            reasons.append(_text_problem(record[name], name))
    reasons += _attempts_problems(record.get('attempts', []))
    label = record.get('session_id', '?')
    return [f'entry {number} ({label}): {reason}' for reason in reasons if reason]


def _attempts_problems(attempts) -> list:
    if not isinstance(attempts, list):
        return [f'attempts must be a list, got {attempts!r}'[:200]]
    reasons = []
    for number, attempt in enumerate(attempts, 1):
        if not isinstance(attempt, dict) or sorted(attempt) != sorted(ATTEMPT_FIELDS):
            reasons.append(f'attempt {number} must have exactly {list(ATTEMPT_FIELDS)}, got '
                           f'{attempt!r}'[:200])
            continue
        reasons += [_text_problem(attempt['started'], f'attempt {number} started'),
                    _text_problem(attempt['ended'], f'attempt {number} ended'),
                    _integer_problem(attempt['exit_code'], f'attempt {number} exit_code')]
    return reasons


def load_study_index(folder) -> list:
    """Return the ``IndexEntry`` list of ``folder``/index.yaml, checked by shape.

    Raises :class:`StudyFolderError` when the folder or its index does not exist and
    :class:`StudyIndexError` (every reason at once) when the index is not a list of entries.
    """
    folder = pathlib.Path(folder)
    path = folder / INDEX_FILE
    if not folder.is_dir():
        raise StudyFolderError(f'{folder}: no such study folder')
    if not path.is_file():
        raise StudyFolderError(f'{path}: no study index (a session run with --study-dir '
                               f'{folder} writes it)')
    try:
        document = bounded_yaml.load(path.read_text(), str(path))
    except (yaml.YAMLError, UnicodeDecodeError) as error:
        raise StudyIndexError(f'{path}: not YAML ({bounded_yaml.describe(error)})') from None
    if document is None:
        document = []
    if not isinstance(document, list):
        raise StudyIndexError(f'{path}: not a list of session entries '
                              f'(a {type(document).__name__})')
    fields = tuple(IndexEntry.__dataclass_fields__)
    reasons = [reason for number, record in enumerate(document, 1)
               for reason in entry_problems(record, number, fields, SESSION_KINDS,
                                            PAPER_CASES)]
    if reasons:
        raise StudyIndexError(f'{path}: ' + '\n'.join(reasons))
    entries = []
    for record in merge_attempts(document):
        values = {name: (str(value) if name in ('started', 'ended') else value)
                  for name, value in record.items()}
        values['attempts'] = [{name: (str(value) if name != 'exit_code' else value)
                               for name, value in attempt.items()}
                              for attempt in values['attempts']]
        entries.append(IndexEntry(**values))
    return entries


def load_tlx_answer(entry, log=print) -> dict:
    """Return the raw TLX of the condition ``entry`` ({scale: score}, {} if none stored).

    Several answers for the session: the last one counts (a notice says so). Raises
    :class:`StudyIndexError` for a TLX file that is not a list of answers of the raw TLX.
    """
    if not entry.tlx_file:
        return {}
    path = pathlib.Path(entry.tlx_file)
    if not path.is_file():
        log(f'{entry.session_id}: no NASA-TLX stored ({path} does not exist)')
        return {}
    try:
        document = bounded_yaml.load(path.read_text(), str(path))
    except (yaml.YAMLError, UnicodeDecodeError) as error:
        raise StudyIndexError(f'{path}: not YAML ({bounded_yaml.describe(error)})') from None
    if not isinstance(document, list) or not all(isinstance(item, dict) for item in document):
        raise StudyIndexError(f'{path}: not a list of NASA-TLX answers')
    answers = [item for item in document if item.get('session_id') == entry.session_id]
    if not answers:
        log(f'{entry.session_id}: no NASA-TLX answer for this session in {path}')
        return {}
    if len(answers) > 1:
        log(f'{entry.session_id}: {len(answers)} NASA-TLX answers in {path}: the last counts')
    scores, reasons = check_tlx(answers[-1].get('scales'))
    if reasons:
        raise StudyIndexError(f'{path}: the answer of {entry.session_id}: ' + '; '.join(reasons))
    return scores


def _session_of(entry, known: dict, log):
    """Return the loaded Session of ``entry`` (from ``known`` or its bag folder), or None."""
    if entry.session_id in known:
        return known[entry.session_id]
    folder = pathlib.Path(entry.bags)
    if not bag_reader.is_session_folder(folder):
        log(f'{entry.session_id}: no bags in {folder}: its columns stay empty')
        return None
    session = load_session(folder)
    for notice in session.notices:
        log(f'{folder}: {notice}')
    known[entry.session_id] = session
    return session


def _engaged_seconds(times: dict) -> dict:
    return {source: entry['seconds'] for source, entry in times.items()}


def _practice_values(session) -> dict:
    """Practice episodes: episodes of the practice bag with at least one HumanAction."""
    if session is None:
        return {'practice_episodes': math.nan, 'practice_human_seconds': math.nan}
    episodes = sum(1 for record in session.human_inputs.values()
                   if record.get('human_source'))
    seconds = sum(entry['seconds'] for entry in human_time(session).values())
    return {'practice_episodes': float(episodes), 'practice_human_seconds': seconds}


def _empty_row(entry) -> dict:
    return {'subject_id': entry.subject_id, 'case': entry.case, 'position': entry.position,
            'kind': entry.kind, 'session_id': '', 'exit_code': None,
            'practice_session_id': '', 'practice_exit_code': None,
            'practice_episodes': math.nan, 'practice_human_seconds': math.nan,
            'human_involved_episodes': math.nan, 'total_episodes': math.nan,
            'evaluation_episodes': math.nan, 'human_seconds': {}, 'converged': None,
            'attempts': [attempt['exit_code'] for attempt in entry.attempts],
            **{key: math.nan for key in ERROR_KEYS}, 'tlx': {}, 'raw_tlx': math.nan,
            'started': str(entry.started)}


def subject_rows(entries: list, sessions=(), log=print) -> list:
    """Return the by-subject rows of the study ``entries`` (IndexEntry).

    One row per condition (its practice ``<session_id>-practice`` in the practice columns) and
    one per practice whose condition is not indexed; ordered by subject, position, start.
    ``sessions``: Sessions already loaded (by session id), else each entry's bag folder is read.
    Human time is by input source over the condition's episodes (training and evaluation);
    errors are the means over its evaluation episodes (Table II "Performance").
    """
    known = {session.session_id: session for session in sessions}
    practices = {entry.session_id: entry for entry in entries if entry.kind == 'practice'}
    used = set()
    rows = []
    for entry in entries:
        if entry.kind != 'condition':
            continue
        row = _empty_row(entry)
        row.update(session_id=entry.session_id, exit_code=entry.exit_code)
        session = _session_of(entry, known, log)
        if session is not None:
            metrics = measures(record_from_bag_session(session))
            row.update({key: metrics[key] for key in ('human_involved_episodes',
                                                      'total_episodes', 'evaluation_episodes',
                                                      'converged') + ERROR_KEYS})
            row['human_seconds'] = _engaged_seconds(human_time(session))
        practice = practices.get(entry.session_id + PRACTICE_SUFFIX)
        if practice is not None and practice.subject_id == entry.subject_id:
            used.add(practice.session_id)
            row.update(practice_session_id=practice.session_id,
                       practice_exit_code=practice.exit_code,
                       **_practice_values(_session_of(practice, known, log)))
        row['tlx'] = load_tlx_answer(entry, log)
        if row['tlx']:
            row['raw_tlx'] = raw_tlx(row['tlx'])
        rows.append(row)
    for practice in practices.values():
        if practice.session_id in used:
            continue
        row = _empty_row(practice)
        row.update(practice_session_id=practice.session_id,
                   practice_exit_code=practice.exit_code,
                   **_practice_values(_session_of(practice, known, log)))
        rows.append(row)
    rows.sort(key=lambda row: (row['subject_id'], row['position'] or 99, row['started']))
    return rows


def outcome(row) -> str:
    """Return how a condition row ended: converged, stopped at the cap, aborted, or failed.

    From its last attempt's exit code and, for a session that finished, whether its bags show
    the convergence rule met (``measures``' converged): a session that ran to its episode cap
    without converging also exits 0, and must not read as a success.
    """
    code = row['exit_code']
    if code is None:
        return ''
    if code == EXIT_OPERATOR_ABORT:
        return 'aborted'
    if code != 0:
        return f'failed (exit {code})'
    if row['converged'] is None:
        return 'finished (no bags)'
    return 'converged' if row['converged'] else 'stopped at the cap'


def source_columns(rows) -> list:
    """Return the input sources of the human-time columns: the contract's, then any other."""
    names = list(source_names().values())
    seen = {source for row in rows for source in row['human_seconds']}
    return names + sorted(seen - set(names))
