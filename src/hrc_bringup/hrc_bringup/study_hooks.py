"""What a session with a subject adds for the study: its index entry, NASA-TLX, owner-only."""

import pathlib
import sys
import time

from hrc_common import bounded_yaml
from hrc_common.session_plan import SessionSettings
from hrc_live.study import (IndexEntry, load_index, load_registry, order_warning, position_of,
                            record_session, returning_start, StudyError)
import yaml


def owner_only(settings: SessionSettings, parameters: dict) -> None:
    """Make every output of a session with a subject id owner-only.

    The umask set at the start makes new files 0600 and folders 0700; a few writers set their
    mode themselves (hrc_common.contract.atomic_write: 0644 by default, e.g. the checkpoints),
    so the session's folders (run, bags, checkpoints; the practice's too) are gone over once
    more at the end: files 0600, folders 0700.
    """
    roots = []
    for session_id in (settings.session_id, settings.session_id + '-practice'):
        roots += [pathlib.Path(settings.runs_dir) / session_id,
                  pathlib.Path(settings.bags_dir) / session_id,
                  pathlib.Path(parameters['agent']['checkpoint_dir']) / session_id]
    for root in roots:
        if not root.is_dir() or root.is_symlink():
            continue
        for path in [root, *root.rglob('*')]:
            if path.is_symlink():
                continue
            try:
                path.chmod(0o700 if path.is_dir() else 0o600)
            except OSError as error:
                print(f'[session] could not make {path} owner-only: {error}', file=sys.stderr)


def warn_out_of_order(settings: SessionSettings, options) -> None:
    """Say at the start when a study condition runs out of its subject's registered order."""
    if not (options.study_dir and settings.subject_id):
        return
    try:
        warning = order_warning(load_registry(options.study_dir),
                                load_index(options.study_dir), settings.subject_id,
                                settings.case)
    except StudyError as error:
        warning = f'the study files cannot be read: {error}'
    if warning:
        print(f'[session] WARNING: {warning}', file=sys.stderr, flush=True)


def start_returning_person(settings: SessionSettings, options) -> None:
    """Start a subject back for a case they finished from the policy learned with them.

    With --study-dir and --subject-id, unless the session resumes, starts from a given
    checkpoint or --fresh-start asks for a new robot: the latest finished session of this
    subject and case in the study index (``hrc_live.study.returning_start``) sets
    ``settings.start_from``; session.yaml and the index entry record it.
    """
    if not (options.study_dir and settings.subject_id) or settings.resume_from \
            or settings.start_from or settings.adapt_from or options.fresh_start:
        return
    try:
        found = returning_start(load_index(options.study_dir), settings.subject_id,
                                settings.case)
    except StudyError as error:
        print(f'[session] WARNING: the study index cannot be read ({error}): a new robot',
              file=sys.stderr, flush=True)
        return
    if found is None:
        return
    session_id, checkpoint = found
    settings.start_from = str(checkpoint)
    print(f'[session] {settings.subject_id} returns to case {settings.case}: the robot starts '
          f'from what it learned with them in session {session_id} ({checkpoint}); '
          '--fresh-start for a new robot', flush=True)


def condition_words(settings: SessionSettings, options) -> str:
    """Return the condition and its place in the subject's order, for the console."""
    words = f'case {settings.case}'
    if not options.study_dir:
        return words
    try:
        subjects = load_registry(options.study_dir)
    except StudyError:
        return words + ' (the study registry cannot be read)'
    subject = next((item for item in subjects if item.id == settings.subject_id), None)
    position = position_of(subjects, settings.subject_id, settings.case)
    if subject is None or not position:
        return words + " (not in the subject's registered order)"
    return f'condition {position} of {len(subject.order)} in the order ({words})'


def index_session(settings: SessionSettings, options, kind: str, started: str,
                  code: int) -> None:
    """Add this run of the session to the study's per-subject index (with --study-dir).

    The TLX file is named only once it holds this session's answers (a run that was aborted,
    or whose person did not answer, names none; a later attempt that stores them does).
    """
    if not options.study_dir:
        return
    session_id = settings.session_id + ('-practice' if kind == 'practice' else '')
    run_dir = pathlib.Path(settings.runs_dir) / session_id
    tlx = run_dir.parent / settings.session_id / 'tlx.yaml'
    entry = IndexEntry(
        subject_id=settings.subject_id, session_id=session_id, case=settings.case, kind=kind,
        position=position_of(load_registry(options.study_dir), settings.subject_id,
                             settings.case),
        started=started, ended=time.strftime('%Y-%m-%dT%H:%M:%S'), exit_code=int(code),
        bags=str((pathlib.Path(settings.bags_dir) / session_id).resolve()),
        run_dir=str(run_dir.resolve()),
        tlx_file=str(tlx.resolve()) if kind == 'condition' and tlx_stored(
            tlx, session_id) else '', start_from=settings.start_from or settings.adapt_from)
    path = record_session(options.study_dir, entry)
    print(f'[session] {kind} {session_id} (exit {int(code)}) recorded in the study index '
          f'{path}', flush=True)


def tlx_stored(path: pathlib.Path, session_id: str) -> bool:
    """Return whether the TLX file ``path`` holds an answer of ``session_id``."""
    try:
        answers = bounded_yaml.load_file(path) or []
    except (OSError, yaml.YAMLError, UnicodeDecodeError):
        return False
    return isinstance(answers, list) and any(
        isinstance(answer, dict) and answer.get('session_id') == session_id
        for answer in answers)


def wait_for_tlx(path: pathlib.Path, session_id: str, executor, timeout: float,
                 stop_reason: list) -> bool:
    """Keep the page up until the person sent the NASA-TLX of this session (or timeout)."""
    print(f'[session] waiting up to {timeout:.0f} s for the NASA-TLX on the page (Ctrl-C '
          f'skips it)', flush=True)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not stop_reason:
        if tlx_stored(path, session_id):
            print(f'[session] NASA-TLX stored in {path}', flush=True)
            return True
        executor.spin_once(timeout_sec=0.2)
    stop_reason.clear()  # Ctrl-C here only skips the questionnaire
    print('[session] no NASA-TLX answer: the session ends without it', flush=True)
    return False
