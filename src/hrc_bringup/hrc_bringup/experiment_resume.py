"""Resuming a sweep: which planned sessions an earlier run of the same folder already finished.

A sweep of the whole study takes hours on a small machine (scripts/rerun_study.py: ~3 h on 2
cores), longer than a machine may stay up. Every finished session is therefore journalled at
once in ``<bags-dir>/<name>/sessions.jsonl`` (one JSON object per line: the task as planned,
its outcome, the git version that ran it), and ``hrc experiment --resume`` runs only the planned
sessions that no earlier run of the folder finished.

A planned session counts as finished when an earlier record has the same *session key* (every
field of the session's configuration that can change its result: case, seed, profile, episode
limits, mode, input, overrides...; not its id or folders, see :data:`NOT_IN_KEY`) and the same
engine, ended with exit code 0, its bag folder is still there, and it was run by the same
version of the code (``git describe --dirty``): a session of another commit is run again, so a
resumed folder holds one version's sessions (a ``-dirty`` version cannot tell two uncommitted
states apart: the runner warns). Plain Python, no ROS.
"""

import json
import pathlib
import shutil

from hrc_common.session_claim import folders_in_use, session_folders

JOURNAL_NAME = 'sessions.jsonl'
MANIFEST_NAME = 'experiment.json'
# SessionSettings fields that name or place a session, or annotate it: they never change what
# the session does, so two sessions that differ only there are the same session.
NOT_IN_KEY = ('session_id', 'bags_dir', 'runs_dir', 'notes', 'subject_id')


def session_key(settings: dict, engine: str) -> str:
    """Return a canonical text of what decides a session's result (settings as plain data)."""
    kept = {name: value for name, value in settings.items() if name not in NOT_IN_KEY}
    # a JSON round trip makes tuples lists and keys strings, as they come back from the files
    return json.dumps({'settings': json.loads(json.dumps(kept)), 'engine': engine},
                      sort_keys=True)


def journal_line(task: dict, outcome: dict, version: str) -> str:
    """Return one journal line (no newline) for a finished session."""
    return json.dumps({'task': task, 'outcome': outcome, 'version': version}, sort_keys=True)


def read_manifest(folder: pathlib.Path) -> dict:
    """Return the folder's ``experiment.json`` ({} when missing or unreadable)."""
    manifest = folder / MANIFEST_NAME
    try:
        return json.loads(manifest.read_text()) if manifest.is_file() else {}
    except (OSError, ValueError):
        return {}


def read_records(folder: pathlib.Path) -> list:
    """Return every session record of earlier runs of ``folder``: dicts task, outcome, version.

    From the manifest of a run that ended (``experiment.json``: its tasks joined with their
    outcomes by session id) and the journal (every session as it finished, also of a run that
    was interrupted); a later record of the same session id replaces an earlier one. Lines or
    files that cannot be read are skipped (a journal cut by a crash ends in a partial line).
    """
    records = {}
    data = read_manifest(folder)
    if data:
        tasks = {task.get('settings', {}).get('session_id'): task
                 for task in data.get('tasks', [])}
        for outcome in data.get('outcomes', []):
            task = tasks.get(outcome.get('session_id'))
            if task is not None:
                records[outcome['session_id']] = {
                    'task': task, 'outcome': outcome,
                    'version': outcome.get('version') or data.get('version', '')}
    journal = folder / JOURNAL_NAME
    if journal.is_file():
        for line in journal.read_text().splitlines():
            try:
                record = json.loads(line)
                records[record['outcome']['session_id']] = record
            except (ValueError, KeyError, TypeError):
                continue
    return list(records.values())


def finished_sessions(folder: pathlib.Path) -> dict:
    """Return {session key: record} of the sessions earlier runs of ``folder`` finished."""
    finished = {}
    for record in read_records(folder):
        outcome, task = record['outcome'], record['task']
        bag = folder / outcome['session_id']
        if outcome.get('exit_code') != 0 or not any(bag.glob('*.mcap')):
            continue
        finished[session_key(task.get('settings', {}), task.get('engine', ''))] = record
    return finished


def split_resumed(planned: list, finished: dict, version: str) -> tuple:
    """Split planned tasks (``(task, settings dict, engine)`` triples) into reused and to run.

    Returns ``(reused, to_run, other_version)``: ``reused`` a list of ``(task, record)`` for
    the tasks an earlier run of this ``version`` finished, ``to_run`` the tasks still to run
    (in the planned order), ``other_version`` the ``(task, record)`` of those among them that
    an earlier run of another version had finished (run again).
    """
    reused, to_run, other_version = [], [], []
    for task, settings, engine in planned:
        record = finished.get(session_key(settings, engine))
        if record is not None and record.get('version') == version:
            reused.append((task, record))
            continue
        to_run.append(task)
        if record is not None:
            other_version.append((task, record))
    return reused, to_run, other_version


def kept_runs(folder: pathlib.Path, reused: list) -> list:
    """Return the earlier runs whose sessions a resumed run keeps (``reused``: (task, record)).

    The folder's manifest lists its runs (``runs``; a manifest from before runs were listed is
    one run); a run is kept when a kept session came from it: by the run's start (journalled
    sessions carry ``run_started``), else, for sessions of such an older manifest, by version.
    A run interrupted before it wrote a manifest is known only from the journal: it is rebuilt
    from its kept sessions (its wall time: the last one's end).
    """
    data = read_manifest(folder)
    runs = data.get('runs') or ([{key: data.get(key) for key in (
        'command', 'started', 'wall_seconds', 'version')}] if data else [])
    starts = {record['outcome'].get('run_started') for _, record in reused}
    versions = {record['version'] for _, record in reused
                if not record['outcome'].get('run_started')}
    kept = [run for run in runs if run.get('started') in starts
            or (run.get('version') in versions and not run.get('sessions_run'))]
    known = {run.get('started') for run in runs}
    interrupted = {}
    for _, record in reused:
        started = record['outcome'].get('run_started')
        if started and started not in known:
            run = interrupted.setdefault(started, {
                'command': '(interrupted; from the journal)', 'started': started,
                'wall_seconds': 0.0, 'version': record['version'], 'sessions_run': 0})
            run['wall_seconds'] = max(run['wall_seconds'],
                                      record['outcome'].get('finished_after', 0.0))
            run['sessions_run'] += 1
    return kept + sorted(interrupted.values(), key=lambda run: run['started'])


EARLIER_RUNS = 'earlier-runs'   # in the sweep's runs folder: files of sessions run again


def earlier_files(tasks: list) -> dict:
    """Return {session id: its folders that hold files} of the tasks (a SessionTask each)."""
    found = {}
    for task in tasks:
        used = folders_in_use(session_folders(task.settings))
        if used:
            found[task.session_id] = used
    return found


def set_aside(tasks: list, runs_folder: pathlib.Path) -> list:
    """Move the folders of ``tasks`` that hold files under ``runs_folder``/earlier-runs.

    A session run again starts in clean folders, and what the earlier run left (a killed
    run's partial bags, a session of another version) is kept, out of the report's way (the
    report reads the bags folder). Returns a line per folder moved.
    """
    moved = []
    for task in tasks:
        folders = session_folders(task.settings)
        if not folders_in_use(folders):
            continue
        attempt = 1
        while (runs_folder / EARLIER_RUNS / f'{task.session_id}-{attempt}').exists():
            attempt += 1
        target = runs_folder / EARLIER_RUNS / f'{task.session_id}-{attempt}'
        for what, folder in folders.items():
            if folder.is_dir():
                destination = target / what.replace(' ', '-')
                destination.parent.mkdir(parents=True, exist_ok=True)
                shutil.move(str(folder), str(destination))
                moved.append(f'{task.session_id}: {what} {folder} -> {destination}')
    return moved
