"""hrc_common.session_claim: one session per id, also when two start at the same moment."""

import multiprocessing
import pathlib

import pytest

from hrc_common.session_claim import (claim_session, CLAIM_FILE, session_folders,
                                      SessionIdTaken)
from hrc_common.session_plan import SessionSettings


def settings_in(folder: pathlib.Path, session_id='case2-seed0-20261206-101500', **more):
    return SessionSettings(session_id=session_id, bags_dir=str(folder / 'bags'),
                           runs_dir=str(folder / 'runs'), **more)


def test_a_free_id_is_claimed_and_then_refused_to_the_next_session(tmp_path):
    assert claim_session(settings_in(tmp_path), generated=False) == ''
    assert (tmp_path / 'runs' / 'case2-seed0-20261206-101500' / CLAIM_FILE).is_file()
    with pytest.raises(SessionIdTaken, match=r'--session-id case2-seed0-20261206-101500: in use '
                       r'by another session \(run folder .* \(1 file\)\): give another '
                       r'--session-id$'):
        claim_session(settings_in(tmp_path), generated=False)


@pytest.mark.parametrize('what', ['run folder', 'checkpoints', 'bags'])
def test_any_folder_of_the_id_with_a_file_makes_it_taken(tmp_path, what):
    folder = session_folders(settings_in(tmp_path))[what]
    folder.mkdir(parents=True)
    (folder / 'x').write_text('')
    with pytest.raises(SessionIdTaken, match=f'{what} {folder}'):
        claim_session(settings_in(tmp_path), generated=False)


def test_the_refusal_names_the_checkpoint_to_resume_from(tmp_path):
    checkpoint = session_folders(settings_in(tmp_path))['checkpoints'] / 'latest.pt'
    checkpoint.parent.mkdir(parents=True)
    checkpoint.write_bytes(b'')
    with pytest.raises(SessionIdTaken, match=f'or continue that session with --resume-from '
                       f'{checkpoint}'):
        claim_session(settings_in(tmp_path), generated=False)


def test_a_resumed_session_continues_its_folders(tmp_path):
    claim_session(settings_in(tmp_path), generated=False)
    resumed = settings_in(tmp_path, resume_from='runs/checkpoints/x/latest.pt')
    assert claim_session(resumed, generated=False) == ''


def test_a_generated_id_that_is_taken_gets_a_suffix_and_says_so(tmp_path):
    claim_session(settings_in(tmp_path), generated=True)
    second = settings_in(tmp_path)
    assert claim_session(second, generated=True) == (
        'session id case2-seed0-20261206-101500 is in use by another session: this one is '
        'case2-seed0-20261206-101500-2')
    assert second.session_id == 'case2-seed0-20261206-101500-2'
    third = settings_in(tmp_path)
    claim_session(third, generated=True)
    assert third.session_id == 'case2-seed0-20261206-101500-3'


def _claim(folder: str, start, results) -> None:
    start.wait()
    try:
        claim_session(settings_in(pathlib.Path(folder)), generated=False)
        results.put('claimed')
    except SessionIdTaken:
        results.put('refused')


def test_of_twelve_starts_at_once_with_one_id_one_claims_it(tmp_path):
    context = multiprocessing.get_context('spawn')
    start, results = context.Event(), context.Queue()
    starters = [context.Process(target=_claim, args=(str(tmp_path), start, results))
                for _ in range(12)]
    for starter in starters:
        starter.start()
    start.set()
    outcomes = sorted(results.get(timeout=120) for _ in starters)
    for starter in starters:
        starter.join(timeout=60)
    assert outcomes == ['claimed'] + ['refused'] * 11
