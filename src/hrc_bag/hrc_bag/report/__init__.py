"""The offline report of recorded sessions: Table II and Fig. 5-7 of the paper (pure, no rclpy).

Four layers, each importing only the ones before it:

* :mod:`hrc_bag.report.loading`: session folders -> :class:`Session` (per-episode records:
  summaries, files, human input sources; configuration; notices). ``load_sessions(paths)`` is
  the entry point other packages (``hrc_study``) build on.
* :mod:`hrc_bag.report.metrics`: Table II values per session and per case (mean, sample
  standard deviation over seeds), Fig. 5-7 data, human time by input source.
* :mod:`hrc_bag.report.study`: a live study's per-subject index (``index.yaml`` of
  ``--study-dir``) with its bags and NASA-TLX answers -> one row per subject and condition.
* :mod:`hrc_bag.report.tables`: Markdown and CSV.
* :mod:`hrc_bag.report.figures`: the PNG figures (matplotlib, Agg).

This module re-exports their public names and writes everything with :func:`write_report`.
Input: session folders written by the recorder (one per case and seed); per session the
EpisodeSummary and SessionStatus messages, the ``hrc_session`` and ``hrc_episode`` records,
and for Fig. 6 the AgentStep and HumanAction messages of one evaluation episode. Topics are
recognized by their type, whatever their (remapped) names. Sessions cut short (a killed
recorder) are read up to their last complete chunk.
"""

import pathlib

from hrc_common.contract import atomic_write, PERSONAL_FILE_MODE
from hrc_common.tlx import TLX_SCALES

from hrc_bag.report.figures import (figure_actions, figure_three_factor,
                                    figure_training_curves)
from hrc_bag.report.loading import (find_sessions, load_session, load_sessions, Session,
                                    topics_of_type)
from hrc_bag.report.metrics import (action_trace, CaseRow, factor_score, FACTOR_AXES,
                                    human_time, mean_and_spread, METRICS, session_metrics,
                                    STRATEGY_ORDER, table2, three_factors, training_curve)
from hrc_bag.report.study import (load_study_index, load_tlx_answer, StudyFolderError,
                                  StudyIndexError, subject_rows)
from hrc_bag.report.tables import (by_subject_csv, by_subject_markdown, human_time_csv,
                                   human_time_markdown, sessions_csv,
                                   STRATEGY_TITLES, table2_csv, table2_markdown,
                                   three_factors_csv)

__all__ = ['action_trace', 'by_subject_csv', 'by_subject_markdown', 'CaseRow', 'factor_score',
           'FACTOR_AXES', 'figure_actions',
           'figure_three_factor', 'figure_training_curves', 'find_sessions', 'human_time',
           'human_time_csv', 'human_time_markdown', 'load_session', 'load_sessions',
           'load_study_index', 'load_tlx_answer', 'StudyFolderError', 'StudyIndexError',
           'subject_rows', 'write_study_report',
           'mean_and_spread', 'METRICS', 'Session', 'session_metrics', 'sessions_csv',
           'STRATEGY_ORDER', 'STRATEGY_TITLES', 'table2', 'table2_csv', 'table2_markdown',
           'three_factors', 'three_factors_csv', 'topics_of_type', 'training_curve',
           'write_report']


def write_report(paths, out_dir, seconds: float = 4.0, start: float = 0.0, log=print) -> dict:
    """Analyse the sessions under ``paths``; write tables and figures into ``out_dir``.

    Returns {'sessions': [...], 'rows': [...], 'files': {name: path}}. Sessions without any
    EpisodeSummary are skipped with a message.
    """
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    sessions = load_sessions(paths, log)
    rows = table2(sessions)
    files = {}
    if not rows:
        return {'sessions': sessions, 'rows': rows, 'files': files}
    texts = {'table2.md': table2_markdown(rows), 'table2.csv': table2_csv(rows),
             'sessions.csv': sessions_csv(sessions), 'fig7_three_factor.csv':
             three_factors_csv(rows), 'human_time.md': human_time_markdown(sessions),
             'human_time.csv': human_time_csv(sessions)}
    for name, text in texts.items():
        (out_dir / name).write_text(text)
        files[name] = out_dir / name
    figures = {'fig5_training.png': lambda target: figure_training_curves(rows, target),
               'fig6_actions.png': lambda target: figure_actions(rows, target, seconds, start),
               'fig7_three_factor.png': lambda target: figure_three_factor(rows, target)}
    for name, draw in figures.items():
        draw(out_dir / name)
        files[name] = out_dir / name
    return {'sessions': sessions, 'rows': rows, 'files': files}


def write_study_report(entries, out_dir, sessions=(), log=print) -> dict:
    """Write by_subject.md and by_subject.csv (mode 0600: subject ids) into ``out_dir``.

    ``entries``: :func:`load_study_index` of the study folder; ``sessions``: Sessions already
    loaded (the others are read from each entry's bag folder). Returns {'rows', 'files'}.
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
