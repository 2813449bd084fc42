"""``hrc bag report``: Table II and Fig. 5-7 from recorded sessions (no ROS graph needed)."""

import argparse
import sys

from hrc_bag.bag_reader import BagError, is_session_folder
from hrc_bag.report import (load_study_index, StudyFolderError, StudyIndexError, write_report,
                            write_study_report)

DESCRIPTION = ('Analyse recorded hrc sessions: writes table2.md, table2.csv, sessions.csv, '
               'human_time.md (.csv: human time by input source), fig5_training.png, '
               'fig6_actions.png, fig7_three_factor.png (+ .csv) into --out. Sessions of the '
               'same case (different seeds) are pooled: mean and sample standard deviation. '
               'With --study-dir (a live study folder, see docs/live_study.md): also '
               'by_subject.md and by_subject.csv from its per-subject index (practice counted '
               'apart, human time by input source, evaluated errors, raw NASA-TLX); without '
               'paths, Table II pools the conditions the index names. '
               'Notices (a file not closed, an unusable metadata.yaml) go to stderr. Exit '
               'codes: 0 done, 1 no session or a file not usable (bag, index, TLX), 2 bad '
               'arguments (no path and no --study-dir, no study index in --study-dir).')


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
    return parser.parse_args(argv)


def _log(text):
    print(f'hrc bag report: {text}', file=sys.stderr)


def _log_lines(error) -> None:
    for line in str(error).splitlines():
        _log(line)


def main(argv=None):
    """Run the report; exit 1 when no session is found or a file is not usable (the reason)."""
    arguments = parse_arguments(sys.argv[1:] if argv is None else argv)
    if not arguments.paths and not arguments.study_dir:
        _log('give session folders (or bag files) and/or --study-dir DIR')
        return 2
    entries, paths = [], list(arguments.paths)
    if arguments.study_dir:
        try:
            entries = load_study_index(arguments.study_dir)
        except StudyFolderError as error:
            _log_lines(error)
            return 2
        except StudyIndexError as error:
            _log_lines(error)
            return 1
        if not entries:
            _log(f'the study index of {arguments.study_dir} lists no session yet')
            return 1
        if not paths:        # Table II of the conditions the index names
            paths = [entry.bags for entry in entries
                     if entry.kind == 'condition' and is_session_folder(entry.bags)]
    files = {}
    try:
        result = write_report(paths, arguments.out, arguments.fig6_seconds,
                              arguments.fig6_start, log=_log) if paths else {
            'sessions': [], 'rows': [], 'files': {}}
        files.update(result['files'])
        if arguments.study_dir:
            files.update(write_study_report(entries, arguments.out, result['sessions'],
                                            log=_log)['files'])
    except (FileNotFoundError, BagError, StudyIndexError) as error:
        _log_lines(error)
        return 1
    if result['rows']:
        print(files['table2.md'].read_text())
        print(files['human_time.md'].read_text())
    elif not arguments.study_dir:
        _log('no session with episode summaries found in ' + ', '.join(paths))
        return 1
    if arguments.study_dir:
        print(files['by_subject.md'].read_text())
    for name, path in files.items():
        print(f'wrote {path}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
