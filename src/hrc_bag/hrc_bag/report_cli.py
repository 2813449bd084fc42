"""``hrc_report``: Table II and Fig. 5-7 from recorded sessions (no ROS graph needed)."""

import argparse
import sys

DESCRIPTION = ('Analyse recorded hrc sessions: writes table2.md, table2.csv, sessions.csv, '
               'human_time.md (.csv: human time by input source), fig5_training.png, '
               'fig6_actions.png, fig7_three_factor.png (+ .csv) into --out. Sessions of the '
               'same case (different seeds) are pooled: mean and sample standard deviation. '
               'Notices (a file not closed, an unusable metadata.yaml) go to stderr.')


def parse_arguments(argv):
    """Return the parsed command line."""
    parser = argparse.ArgumentParser(prog='hrc_report', description=DESCRIPTION)
    parser.add_argument('paths', nargs='+',
                        help='session folders (bags/<session_id>), folders of session folders '
                             '(bags/), or single episode files')
    parser.add_argument('--out', default='report', help='output folder (default: report)')
    parser.add_argument('--fig6-seconds', type=float, default=4.0,
                        help='length of the Fig. 6 window (s of simulation time, default 4)')
    parser.add_argument('--fig6-start', type=float, default=0.0,
                        help='start of the Fig. 6 window in the evaluation episode (s)')
    return parser.parse_args(argv)


def main(argv=None):
    """Run the report; exit 1 when no session is found or a file is not MCAP (the reason)."""
    arguments = parse_arguments(sys.argv[1:] if argv is None else argv)
    from hrc_bag.bag_reader import BagError
    from hrc_bag.report import write_report

    def log(text):
        print(f'hrc_report: {text}', file=sys.stderr)

    try:
        result = write_report(arguments.paths, arguments.out, arguments.fig6_seconds,
                              arguments.fig6_start, log=log)
    except (FileNotFoundError, BagError) as error:
        for line in str(error).splitlines():
            log(line)
        return 1
    if not result['rows']:
        log('no session with episode summaries found in ' + ', '.join(arguments.paths))
        return 1
    print(result['files']['table2.md'].read_text())
    print(result['files']['human_time.md'].read_text())
    for name, path in result['files'].items():
        print(f'wrote {path}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
