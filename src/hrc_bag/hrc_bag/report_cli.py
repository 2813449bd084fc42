"""``hrc bag report``: the report of recorded sessions (no ROS graph needed).

Table II, Fig. 5-7, sessions.csv, the person's time, human time by input source
(:func:`hrc_bag.report.write_report`, the same report ``hrc results`` writes beside its
findings) and, with ``--study-dir``, the table by subject.
"""

import argparse
import sys

from hrc_bag.bag_reader import BagError, is_session_folder
from hrc_bag.report import (load_sessions, load_study_index, POOL_OPTION, pooling_refusal,
                            record_from_bag_session, StudyFolderError, StudyIndexError,
                            write_report, write_study_report)
from hrc_bag.report.records import session_order

DESCRIPTION = ("Analyse recorded hrc sessions: writes table2.md (Table II and the person's "
               'time), table2.csv, sessions.csv, human_time.md (.csv: human time by input '
               'source), fig5_training.png, fig6_actions.png, fig7_three_factor.png (+ .csv) '
               'into --out. Sessions of the same case (different seeds) are pooled: mean and '
               '95% BCa interval. Sessions of different learning configurations are refused '
               f'unless {POOL_OPTION}. With --study-dir (a live study folder, see '
               'docs/live_study.md): also by_subject.md and by_subject.csv from its '
               'per-subject index (practice counted apart, human time by input source, '
               'evaluated errors, raw NASA-TLX); without paths, Table II pools the conditions '
               'the index names. Notices (a file not closed, an unusable metadata.yaml) go to '
               'stderr. Exit codes: 0 done, 1 no session or a file not usable (bag, index, '
               'TLX), 2 bad arguments (no path and no --study-dir, no study index in '
               '--study-dir, sessions of different learning configurations).')


def parse_arguments(argv):
    """Return the parsed command line."""
    parser = argparse.ArgumentParser(prog='hrc bag report', description=DESCRIPTION)
    parser.add_argument('paths', nargs='*',
                        help='session folders (bags/<session_id>), folders of session folders '
                             '(bags/), or single episode files (optional with --study-dir)')
    parser.add_argument('--study-dir', default='', metavar='DIR',
                        help='a live study folder (index.yaml of session --study-dir): write '
                             'the by-subject table too')
    parser.add_argument('--out', default='report', help='output folder (default: report)')
    parser.add_argument('--fig6-seconds', type=float, default=4.0,
                        help='length of the Fig. 6 window (s of simulation time, default 4)')
    parser.add_argument('--fig6-start', type=float, default=0.0,
                        help='start of the Fig. 6 window in the evaluation episode (s)')
    parser.add_argument(POOL_OPTION, action='store_true',
                        help='pool sessions that differ in learning configuration (and, given '
                             'by path, in who acted as the person, episode limits, practice '
                             'only or repeats)')
    return parser.parse_args(argv)


def _log(text):
    print(f'hrc bag report: {text}', file=sys.stderr)


def _log_lines(error) -> None:
    for line in str(error).splitlines():
        _log(line)


def _study_entries(arguments) -> tuple:
    """Return (index entries, exit code or None) of ``--study-dir`` (no entries without it)."""
    if not arguments.study_dir:
        return [], None
    try:
        entries = load_study_index(arguments.study_dir)
    except StudyFolderError as error:
        _log_lines(error)
        return [], 2
    except StudyIndexError as error:
        _log_lines(error)
        return [], 1
    if not entries:
        _log(f'the study index of {arguments.study_dir} lists no session yet')
        return [], 1
    return entries, None


def _write(arguments, entries, paths) -> tuple:
    """Load the sessions and write the report; return ({name: path}, sessions, exit code)."""
    bag_sessions = load_sessions(paths, log=_log) if paths else []
    records = sorted(map(record_from_bag_session, bag_sessions), key=session_order)
    # a study's conditions differ on purpose (subjects, aborted ones): its by-subject table
    # says how each went; sessions given by path are pooled as seeds
    refusal = pooling_refusal(records, arguments.pool_configurations,
                              strict=not arguments.study_dir)
    if refusal:
        _log_lines(refusal)
        return {}, records, 2
    files = {}
    if records:
        files.update(write_report(records, arguments.out, arguments.fig6_seconds,
                                  arguments.fig6_start)['files'])
    if entries:
        files.update(write_study_report(entries, arguments.out, bag_sessions,
                                        log=_log)['files'])
    return files, records, None


def main(argv=None):
    """Run the report; exit 1 when no session is found or a file is not usable (the reason)."""
    arguments = parse_arguments(sys.argv[1:] if argv is None else argv)
    if not arguments.paths and not arguments.study_dir:
        _log('give session folders (or bag files) and/or --study-dir DIR')
        return 2
    entries, code = _study_entries(arguments)
    if code is not None:
        return code
    paths = list(arguments.paths) or [      # Table II of the conditions the index names
        entry.bags for entry in entries
        if entry.kind == 'condition' and is_session_folder(entry.bags)]
    try:
        files, records, code = _write(arguments, entries, paths)
    except (FileNotFoundError, BagError, StudyIndexError) as error:
        _log_lines(error)
        return 1
    if code is not None:
        return code
    if records:
        print(files['table2.md'].read_text())
        print(files['human_time.md'].read_text())
    elif not entries:
        _log('no session with episode summaries found in ' + ', '.join(paths))
        return 1
    if entries:
        print(files['by_subject.md'].read_text())
    for path in files.values():
        print(f'wrote {path}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
