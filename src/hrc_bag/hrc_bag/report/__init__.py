"""The report of 1..N recorded sessions (pure, no rclpy).

Table II, Fig. 5-7, sessions.csv, the person's time, human time by input source and the table
by subject.
``hrc bag report`` and ``hrc results`` (``hrc_study``, which adds the findings, the
convergence analysis and the strategy chooser) both write it with :func:`write_report`.
Layers, each importing only the ones before it:

* :mod:`.loading`: session folders -> :class:`Session` (decoded summaries, statuses, files,
  human input sources, configuration, notices);
* :mod:`.session_config`, :mod:`.records`: the values of ``session.yaml`` the report uses and
  the :class:`SessionRecord` of a session, its per-session :func:`measures`;
  :func:`load_records` reads records from bags;
* :mod:`.intervals`: Table II's 95% BCa intervals; :mod:`.configurations`: the learning
  configurations of the sessions (a report refuses to pool different ones unless told);
* :mod:`.metrics`, :mod:`.curves`: groupings by case, Fig. 5-7 data, human time;
* :mod:`.study`: a live study's per-subject index with its bags and NASA-TLX answers;
* :mod:`.tables`, :mod:`.subject_tables`: Markdown and CSV; :mod:`.figures`: the PNG figures.

Input: session folders written by the recorder (one per case and seed); topics are recognized
by their type, whatever their (remapped) names. Sessions cut short (a killed recorder) are read
up to their last complete chunk. One session: Table II holds its values; several sessions of a
case (seeds): their mean with its interval.
"""

import pathlib

from hrc_common.contract import atomic_write, PERSONAL_FILE_MODE
from hrc_common.tlx import TLX_SCALES

from hrc_bag.report import figures, tables
from hrc_bag.report.configurations import describe, pooling_refusal, POOL_OPTION
from hrc_bag.report.configurations import configurations as learning_configurations
from hrc_bag.report.intervals import RESAMPLES
from hrc_bag.report.loading import find_sessions, load_session, load_sessions, Session
from hrc_bag.report.metrics import (by_case, case_measures, human_time, primary_profile,
                                    three_factors)
from hrc_bag.report.records import load_records, record_from_bag_session, SessionRecord
from hrc_bag.report.study import (load_study_index, load_tlx_answer, StudyFolderError,
                                  StudyIndexError, subject_rows)
from hrc_bag.report.subject_tables import by_subject_csv, by_subject_markdown

__all__ = ['by_case', 'describe', 'find_sessions', 'human_time', 'learning_configurations',
           'load_records', 'load_session', 'load_sessions', 'load_study_index',
           'load_tlx_answer', 'POOL_OPTION', 'pooling_refusal', 'primary_profile',
           'record_from_bag_session', 'Session', 'SessionRecord', 'StudyFolderError',
           'StudyIndexError', 'subject_rows', 'table2_document', 'write_report',
           'write_study_report']


def _profiles(sessions) -> list:
    primary = primary_profile(sessions)
    return [primary] + sorted({session.profile for session in sessions} - {primary})


def table2_document(sessions, intervals_by_profile: dict) -> str:
    """Return table2.md: Table II and the person's time per profile (the primary first)."""
    configurations = describe(learning_configurations(sessions))
    parts = []
    for profile in _profiles(sessions):
        groups = by_case(sessions, profile)
        parts += [f'## Table II, profile `{profile}`: mean [95% interval] over seeds', '',
                  f'Learning configuration: {configurations}.', '',
                  tables.table2_markdown(groups, intervals=intervals_by_profile[profile]),
                  ' '.join([tables.TABLE2_NOTE, tables.OUTCOME_NOTE, tables.CHATTER_NOTE]),
                  '',
                  f"## The person's time, profile `{profile}`", '',
                  tables.person_time_markdown(case_measures(sessions, profile)),
                  tables.PERSON_TIME_NOTE, '']
    return '\n'.join(parts)


def write_report(sessions, out_dir, seconds: float = 4.0, start: float = 0.0, seed: int = 0,
                 resamples: int = RESAMPLES) -> dict:
    """Write the report of ``sessions`` (SessionRecords, :func:`load_records`) into ``out_dir``.

    Files: table2.md (Table II and the person's time per profile), table2.csv, sessions.csv,
    human_time.md and .csv, fig5_training.png, fig6_actions.png (``seconds`` of the evaluation
    episode from ``start``), fig7_three_factor.png and .csv (figures and CSVs: the primary
    profile). ``seed`` and ``resamples``: the bootstrap of Table II's intervals. Returns
    {'profile', 'groups', 'intervals', 'factors', 'files': {name: path}}.
    """
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    profile = primary_profile(sessions)
    primary = [session for session in sessions if session.profile == profile]
    intervals = {name: tables.table2_intervals(by_case(sessions, name), seed, resamples)
                 for name in _profiles(sessions)}
    groups = by_case(sessions, profile)
    factors = three_factors(primary, seed)
    texts = {'table2.md': table2_document(sessions, intervals),
             'table2.csv': tables.table2_csv(groups, intervals[profile]),
             'sessions.csv': tables.sessions_csv(sessions),
             'human_time.md': tables.human_time_markdown(sessions),
             'human_time.csv': tables.human_time_csv(sessions),
             'fig7_three_factor.csv': tables.three_factors_csv(factors)}
    files = {}
    for name, text in texts.items():
        (out_dir / name).write_text(text)
        files[name] = out_dir / name
    drawings = {
        'fig5_training.png': lambda path: figures.figure_training(primary, profile, path),
        'fig6_actions.png': lambda path: figures.figure_actions(primary, profile, path,
                                                                seconds, start),
        'fig7_three_factor.png': lambda path: figures.figure_three_factor(
            primary, profile, path, factors)}
    for name, draw in drawings.items():
        draw(out_dir / name)
        files[name] = out_dir / name
    return {'profile': profile, 'groups': groups, 'intervals': intervals[profile],
            'factors': factors, 'files': files}


def write_study_report(entries, out_dir, sessions=(), log=print) -> dict:
    """Write by_subject.md and by_subject.csv (mode 0600: subject ids) into ``out_dir``.

    ``entries``: :func:`load_study_index` of the study folder; ``sessions``: bag Sessions
    already loaded (the others are read from each entry's bag folder). Returns {'rows', 'files'}.
    """
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    rows = subject_rows(entries, sessions, log)
    files = {}
    for name, text in (('by_subject.md', by_subject_markdown(rows, TLX_SCALES)),
                       ('by_subject.csv', by_subject_csv(rows, TLX_SCALES))):
        atomic_write(out_dir / name, text, mode=PERSONAL_FILE_MODE)
        files[name] = out_dir / name
    return {'rows': rows, 'files': files}
