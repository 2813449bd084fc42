"""The command line of ``hrc results``: its parser, light to import.

``hrc results --help`` is answered from here without loading scipy or matplotlib (the study's
modules load them); ``hrc_study.results_cli.parse_arguments`` checks the values.
"""

import argparse

DESCRIPTION = ('Write results.md (Table II with 95% BCa intervals, censored episodes to '
               "convergence, the paper's findings with paired, censoring-aware, "
               'Holm-corrected tests, the strategy chooser) and, in results/, the report '
               '`hrc bag report` writes (Fig. 5-7, sessions.csv, ...) from recorded sessions '
               'of one learning configuration.')


def build_parser() -> argparse.ArgumentParser:
    """Return the parser of ``hrc results`` (its flags and help)."""
    parser = argparse.ArgumentParser(prog='hrc results', description=DESCRIPTION)
    parser.add_argument('paths', nargs='+', help='experiment folders (bags/<experiment>) or '
                        'session folders')
    parser.add_argument('--out', default='results',
                        help="folder of results.md (default results; the repository's pages: "
                             '--out docs)')
    parser.add_argument('--priorities', default='',
                        help='strategy chooser weights, e.g. performance=3,human=1,time=1, or '
                        'a preset: balanced, "performance first", "least human time", '
                        '"fastest training"')
    parser.add_argument('--seed', type=int, default=0, help='bootstrap seed (default 0)')
    parser.add_argument('--pool-configurations', action='store_true',
                        help='pool sessions that differ in learning configuration, in who '
                        'acted as the person, in episode limits, practice-only sessions or '
                        'repeats (refused without: exit 2, every reason)')
    parser.add_argument('--note', default='',
                        help='a paragraph put under the run description (e.g. the commit)')
    return parser
