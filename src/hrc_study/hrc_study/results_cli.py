"""``hrc_results``: docs/results.md and its figures from the bags of an experiment.

    hrc results bags/<experiment> --out docs/
    hrc results bags/<experiment> --out /tmp/r --priorities human=3,time=1

Writes ``<out>/results.md`` and ``<out>/results/`` (Fig. 5-7, convergence curves,
sessions.csv), prints the findings, the targets and the strategy ranking. Exit codes: 0 done,
1 no session found, 2 bad arguments.
"""

import argparse
import shlex
import sys

from hrc_study.chooser import choice_markdown, parse_priorities
from hrc_study.loading import load_sessions
from hrc_study.results_doc import read_experiment, write_results

DESCRIPTION = ('Write results.md (Table II with 95%% intervals, censored episodes to '
               "convergence, the paper's findings with paired, censoring-aware, "
               'Holm-corrected tests, the strategy '
               'chooser) and its figures from recorded sessions.')


def parse_arguments(argv):
    """Return the parsed command line; exit 2 with every reason on bad input."""
    parser = argparse.ArgumentParser(prog='hrc results', description=DESCRIPTION)
    parser.add_argument('paths', nargs='+', help='experiment folders (bags/<experiment>) or '
                        'session folders')
    parser.add_argument('--out', default='docs', help='folder of results.md (default docs)')
    parser.add_argument('--priorities', default='',
                        help='strategy chooser weights, e.g. performance=3,human=1,time=1, or '
                        'a preset: balanced, "performance first", "least human time", '
                        '"fastest training"')
    parser.add_argument('--seed', type=int, default=0, help='bootstrap seed (default 0)')
    parser.add_argument('--intervals', default='bca', choices=['bca', 'student-t'],
                        help="Table II intervals: bca (BCa bootstrap within each quantity's "
                        'physical range, default) or student-t (the tables before issue 23)')
    parser.add_argument('--note', default='',
                        help='a paragraph put under the run description (e.g. the commit)')
    arguments = parser.parse_args(argv)
    if arguments.priorities:
        try:
            arguments.weights = parse_priorities(arguments.priorities)
        except ValueError as error:
            parser.error(f'--priorities: {error}')
    else:
        arguments.weights = None
    return arguments


def main(argv=None) -> int:
    """Run the study's report."""
    argv = sys.argv[1:] if argv is None else argv
    arguments = parse_arguments(argv)
    def log(text):
        print(f'hrc_results: {text}', file=sys.stderr)

    try:
        sessions = load_sessions(arguments.paths, log=log)
    except (FileNotFoundError, ValueError) as error:   # ValueError: BagError, a bad file
        log(str(error))
        return 1
    if not sessions:
        log('no session with episode summaries in ' + ', '.join(arguments.paths))
        return 1
    command = 'hrc results ' + ' '.join(shlex.quote(arg) for arg in argv)
    try:
        result = write_results(sessions, arguments.out, command,
                               read_experiment(arguments.paths), arguments.weights,
                               arguments.seed, arguments.note,
                               intervals=arguments.intervals)
    except ValueError as error:
        log(str(error))
        return 1
    print('findings:')
    for finding in result['findings']:
        print(f'  ({finding.key}) {finding.claim}: {finding.verdict.upper()} '
              f'(Holm p = {finding.p_holm:.3g}; {finding.reason})')
    print('targets:')
    for target, measured, met in result['targets']:
        verdict = 'n/a' if met is None else ('met' if met else 'NOT met')
        print(f'  [{verdict}] {target}: {measured}')
    name = 'your priorities' if arguments.weights else 'balanced'
    if name in result['choices']:
        print('strategy chooser:\n' + choice_markdown(result['choices'][name], name))
    else:
        print('strategy chooser: not computed (sessions of fewer than two strategies)')
    for path in result['files'].values():
        print(f'wrote {path}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
