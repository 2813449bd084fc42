"""A session's folders are its own: an id in use is refused unless the session resumes (pure).

A session writes three folders named by its id: ``<runs-dir>/<id>`` (logs, parameters, report),
``<runs-dir>/checkpoints/<id>`` (the agent's checkpoints) and ``<bags-dir>/<id>`` (the bags).
A second run with the same id would file its episodes as attempts of the first, overwrite its
``final.pt`` and give the report one session made of two. So a new session claims its id: the
folders must hold no file, and a claim file created with ``O_EXCL`` in the run folder makes two
starts at the same moment exclusive (the second sees it). A session that resumes
(``--resume-from``) continues its folders and claims nothing. An id the runner made itself
(``case<N>-seed<S>-<time>``, one a second) gets a suffix when it is taken, and says so.
"""

import os
import pathlib

from hrc_common.session_control import LATEST_CHECKPOINT

CLAIM_FILE = '.session-claim'       # in <runs-dir>/<id>: the session that owns the id
MAX_SUFFIX = 99                     # generated ids tried: <id>-2 .. <id>-99


class SessionIdTaken(ValueError):
    """The session id names folders of another session (the message says which, what to do)."""


def session_folders(settings, session_id: str = '') -> dict:
    """Return {what: folder} of the session (run folder, checkpoints, bags)."""
    session_id = session_id or settings.session_id
    runs = pathlib.Path(settings.runs_dir)
    return {'run folder': runs / session_id, 'checkpoints': runs / 'checkpoints' / session_id,
            'bags': pathlib.Path(settings.bags_dir) / session_id}


def folders_in_use(folders: dict) -> list:
    """Return '<what> <folder> (<n> files)' of each folder that holds a file (the claim too)."""
    used = []
    for what, folder in folders.items():
        if folder.is_dir():
            count = sum(1 for path in folder.rglob('*') if not path.is_dir())
            if count:
                used.append(f'{what} {folder} ({count} file{"s" if count != 1 else ""})')
    return used


def _take(folders: dict) -> bool:
    """Claim the folders if no file is in them; False when another session has them."""
    if folders_in_use(folders):
        return False
    run_folder = folders['run folder']
    run_folder.mkdir(parents=True, exist_ok=True)
    try:
        descriptor = os.open(run_folder / CLAIM_FILE, os.O_WRONLY | os.O_CREAT | os.O_EXCL,
                             0o644)
    except FileExistsError:     # another start claimed it between the check and now
        return False
    with os.fdopen(descriptor, 'w') as stream:
        stream.write(f'pid {os.getpid()}\n')
    return True


def claim_session(settings, generated: bool) -> str:
    """Claim ``settings.session_id`` (changed to a free one if ``generated``); return a notice.

    Raises SessionIdTaken for an id given by the user that another session holds: the message
    names its folders and the two ways on (another id, or resume that session).
    """
    if settings.resume_from:
        return ''
    base = settings.session_id
    if _take(session_folders(settings, base)):
        return ''
    if not generated:
        used = folders_in_use(session_folders(settings, base)) or [
            f'run folder {session_folders(settings, base)["run folder"]} (a session starting '
            'now)']
        checkpoint = session_folders(settings, base)['checkpoints'] / LATEST_CHECKPOINT
        resume = (f', or continue that session with --resume-from {checkpoint}'
                  if checkpoint.is_file() else '')
        raise SessionIdTaken(f'--session-id {base}: in use by another session ('
                             + '; '.join(used) + f'): give another --session-id{resume}')
    for suffix in range(2, MAX_SUFFIX + 1):
        candidate = f'{base}-{suffix}'
        if _take(session_folders(settings, candidate)):
            settings.session_id = candidate
            return f'session id {base} is in use by another session: this one is {candidate}'
    raise SessionIdTaken(f'session ids {base} to {base}-{MAX_SUFFIX} are all in use: give '
                         '--session-id')
