"""``hrc_results``: docs/results.md and its figures from the bags of an experiment.

    hrc results bags/<experiment> --out docs/
    hrc results bags/<experiment> --out /tmp/r --priorities human=3,time=1

Writes ``<out>/results.md`` and ``<out>/results/`` (Fig. 5-7, convergence curves,
sessions.csv), prints the findings, the targets and the strategy ranking. On stderr, the
progress with the time left: one step per session loaded, then one for the tables, findings
and figures (a bar on a terminal, plain lines when piped). Sessions of different learning
configurations (``session.yaml``'s ``learning``) are refused unless ``--pool-configurations``.
Exit codes: 0 done, 1 no session found or a file not usable, 2 bad arguments (sessions of
different learning configurations among them).
"""

import shlex
import sys

from hrc_bag.report import find_sessions, load_records, pooling_refusal
from hrc_bag.report.records import session_order
from hrc_common.time_left import TimeLeft

from hrc_study.chooser import choice_markdown, parse_priorities
from hrc_study.results_args import build_parser
from hrc_study.results_doc import write_results
from hrc_study.results_tables import read_experiment


def parse_arguments(argv):
    """Return the parsed command line; exit 2 with every reason on bad input."""
    parser = build_parser()
    arguments = parser.parse_args(argv)
    if arguments.priorities:
        try:
            arguments.weights = parse_priorities(arguments.priorities)
        except ValueError as error:
            parser.error(f'--priorities: {error}')
    else:
        arguments.weights = None
    return arguments


def load_with_progress(folders, progress, log) -> tuple:
    """Return (SessionRecords sorted as ``load_records`` sorts them, problems), one at a time.

    Each folder is one step of ``progress``; a folder that cannot be read is a problem (its
    message), and the others are still read so that every problem is named at once.
    """
    sessions, problems = [], []
    for done, folder in enumerate(folders, start=1):
        try:
            loaded = load_records([folder], log=log)
        except (FileNotFoundError, ValueError) as error:   # ValueError: BagError, a bad file
            problems.append(str(error))
            loaded = []
        sessions += loaded
        progress.show(done, f'hrc_results: read {folder.name} ({len(loaded)} session'
                      f'{"" if len(loaded) == 1 else "s"} with episode summaries)')
    sessions.sort(key=session_order)
    return sessions, problems


def main(argv=None) -> int:
    """Run the study's report."""
    argv = sys.argv[1:] if argv is None else argv
    arguments = parse_arguments(argv)
    def log(text):
        print(f'hrc_results: {text}', file=sys.stderr)

    try:
        folders = find_sessions(arguments.paths)
    except FileNotFoundError as error:
        log(str(error))
        return 1
    # One step per session folder, then one for the tables, findings and figures (a
    # modelling choice for the estimate: that last step is counted as long as a load).
    progress = TimeLeft(len(folders) + 1, 'steps', stream=sys.stderr)
    sessions, problems = load_with_progress(folders, progress, log)
    if problems:                        # every unreadable session at once
        progress.close()
        for problem in problems:
            log(problem)
        return 1
    if not sessions:
        progress.close()
        log('no session with episode summaries in ' + ', '.join(arguments.paths))
        return 1
    refusal = pooling_refusal(sessions, arguments.pool_configurations, strict=True)
    if refusal:
        progress.close()
        for line in refusal.splitlines():
            log(line)
        return 2
    command = 'hrc results ' + ' '.join(shlex.quote(arg) for arg in argv)
    try:
        result = write_results(sessions, arguments.out, command,
                               read_experiment(arguments.paths), arguments.weights,
                               arguments.seed, arguments.note)
    except OSError as error:     # --out not writable: the user's to mend (exit 1, no traceback)
        progress.close()
        log(f'cannot write the results to {arguments.out}: {error}')
        return 1
    # Any other error in the statistics is a defect of hrc and keeps its traceback: a
    # ValueError caught here once made scipy's failure on a one-pair comparison look like a
    # user mistake.
    progress.show(len(folders) + 1, f'hrc_results: wrote the tables, findings and figures to '
                  f'{arguments.out}')
    progress.close()
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
