"""A subject back for a case they finished starts from the checkpoint of that session.

The study index (written by the session runner) is looked up by subject and case: the latest
condition that ran to its end and left final.pt; ``hrc session`` sets --start-from from it
unless it resumes, is given a checkpoint, or is told --fresh-start.
"""

import argparse

from hrc_bringup.study_hooks import start_returning_person
from hrc_common.session_plan import SessionSettings
from hrc_common.study_index import IndexEntry
from hrc_live.study import record_session, returning_start


def entry(tmp_path, session_id, case, exit_code, ended, subject='P07', checkpoint=True):
    runs = tmp_path / 'runs'
    if checkpoint:
        folder = runs / 'checkpoints' / session_id
        folder.mkdir(parents=True, exist_ok=True)
        (folder / 'final.pt').write_bytes(b'x')
    return IndexEntry(subject_id=subject, session_id=session_id, case=case, kind='condition',
                      position=1, started=ended, ended=ended, exit_code=exit_code,
                      bags=str(tmp_path / 'bags' / session_id),
                      run_dir=str(runs / session_id))


def study(tmp_path):
    folder = tmp_path / 'study'
    folder.mkdir()
    for item in (entry(tmp_path, 'a', 2, 0, '2026-12-01T10:00:00'),
                 entry(tmp_path, 'b', 2, 0, '2026-12-02T10:00:00'),       # the latest finished
                 entry(tmp_path, 'c', 2, 3, '2026-12-03T10:00:00'),       # aborted: not it
                 entry(tmp_path, 'd', 2, 0, '2026-12-04T10:00:00', checkpoint=False),
                 entry(tmp_path, 'e', 4, 0, '2026-12-05T10:00:00'),       # another case
                 entry(tmp_path, 'f', 2, 0, '2026-12-06T10:00:00', subject='P08')):
        record_session(folder, item)
    return folder


def test_the_latest_finished_session_of_the_subject_and_case(tmp_path):
    from hrc_live.study import load_index

    entries = load_index(study(tmp_path))
    session_id, checkpoint = returning_start(entries, 'P07', 2)
    assert session_id == 'b'
    assert checkpoint == tmp_path / 'runs' / 'checkpoints' / 'b' / 'final.pt'
    assert returning_start(entries, 'P07', 6) is None
    assert returning_start(entries, 'P09', 2) is None


def test_the_runner_starts_from_it_unless_told_otherwise(tmp_path, capsys):
    folder = study(tmp_path)
    settings = SessionSettings(case=2, subject_id='P07')
    start_returning_person(settings, argparse.Namespace(study_dir=str(folder), fresh_start=False))
    assert settings.start_from.endswith('checkpoints/b/final.pt')
    out = capsys.readouterr().out
    assert 'P07 returns to case 2' in out and 'session b' in out and '--fresh-start' in out
    fresh = SessionSettings(case=2, subject_id='P07')
    start_returning_person(fresh, argparse.Namespace(study_dir=str(folder), fresh_start=True))
    resumed = SessionSettings(case=2, subject_id='P07', resume_from='x.pt')
    start_returning_person(resumed, argparse.Namespace(study_dir=str(folder),
                                                       fresh_start=False))
    assert fresh.start_from == '' and resumed.start_from == ''
