"""``hrc``: the one command line of hrc, with verbs in the style of ``ros2``.

    hrc --help                                  # the verbs
    hrc session --case 2 --seed 0               # one session as the ROS graph
    hrc session --engine inprocess --case 2     # the same session in one process
    hrc bag report bags/<session>               # Table II and the figures of a session

Each verb runs the ``main(argv)`` of the module that owns the job (the session runner of this
package, the report of hrc_bag, the study tools of hrc_live, ...); ``hrc <verb> --help`` prints
that verb's own help followed by an example. The flags that several verbs take are spelled the
same everywhere: ``--case``, ``--seed``, ``--engine graph|inprocess``, ``--human
sim|auto|device|joy|model|script``, ``--profile`` (a simulated-human profile), ``--set
NODE.PARAM=VALUE``. The nodes keep their own executables (``ros2 run hrc_sim_node sim_node``
...). Benchmarks are scripts, not verbs (``bench/``, ``python bench/gym_ppo_vs_sb3.py``).

Exit codes: those of the verb; 2 for an unknown verb or bad flags (every reason at once, no
traceback); 130 on Ctrl-C.
"""

import dataclasses
import difflib
import os
import sys
import textwrap
import typing

from hrc_common.executables import executable_path

from hrc_bringup import bag_info

PROG = 'hrc'
EXIT_BAD_ARGUMENTS = 2
EXIT_INTERRUPTED = 130      # 128 + SIGINT, as a shell reports it
ENGINES = ('graph', 'inprocess')
USAGE_WIDTH = 99     # columns of `hrc --help`


@dataclasses.dataclass(frozen=True)
class Verb:
    """One verb: its words after ``hrc``, what it does (one line), an example, its runner.

    ``help``, for a verb whose runner's module loads torch, PyBullet, ray, scipy or matplotlib
    when imported: parses the arguments with the verb's own parser built in a light module, so
    that ``--help`` prints the same text without those imports (argparse exits after it).
    """

    words: tuple
    summary: str
    example: str
    run: typing.Callable[[list], int]
    help: typing.Optional[typing.Callable[[list], None]] = None

    @property
    def name(self) -> str:
        return ' '.join(self.words)


# Each runner imports its module when the verb is chosen, not at the top of this module:
# `hrc --help` and `hrc operator status` must not load torch, PyBullet or rclpy's message
# packages of every other verb (seconds each on this machine). The imports are plain imports,
# so the layer test still sees every package this one depends on.

def _session(argv: list) -> int:
    engine, rest, problems = take_engine(argv)
    if problems:
        return refuse('session', problems)
    if engine == 'inprocess':
        from hrc_engine import inprocess_session  # lazy: torch and PyBullet (see above)
        return inprocess_session.main(rest)
    from hrc_bringup import session  # lazy: rclpy and the message packages (see above)
    return session.main(rest)


def _session_help(argv: list) -> None:
    engine, rest, problems = take_engine(argv)
    if problems:
        return      # the runner refuses them, every reason at once
    if engine == 'inprocess':
        from hrc_engine.inprocess_args import build_parser  # lazy: only for --help
    else:
        from hrc_bringup.session_args import build_parser  # lazy: only for --help
    build_parser().parse_args(rest)


def _experiment_help(argv: list) -> None:
    from hrc_bringup.experiment_args import build_parser  # lazy: only for --help
    build_parser().parse_args(argv)


def _experiment(argv: list) -> int:
    from hrc_bringup import experiment  # lazy: torch, PyBullet, ray (see above)
    return experiment.main(argv)


def _bag_report(argv: list) -> int:
    from hrc_bag import report_cli  # lazy: matplotlib (see above)
    return report_cli.main(argv)


def _bag_replay(argv: list) -> int:
    return bag_info.replay(argv, executable_path('hrc_bag', 'replay_node'))


def _results(argv: list) -> int:
    from hrc_study import results_cli  # lazy: matplotlib, scipy (see above)
    return results_cli.main(argv)


def _results_help(argv: list) -> None:
    from hrc_study.results_args import build_parser  # lazy: only for --help
    build_parser().parse_args(argv)


def _study(argv: list) -> int:
    from hrc_live import study_cli  # lazy: the verb's packages (see above)
    return study_cli.main(study_dir_first(argv))


def _operator(argv: list) -> int:
    from hrc_live import operator_cli  # lazy: rclpy (see above)
    return operator_cli.main(argv)


def _joystick_setup(argv: list) -> int:
    from hrc_live import joystick_setup  # lazy: the verb's packages (see above)
    return joystick_setup.main(argv)


def _partners_clone(argv: list) -> int:
    from hrc_partners import clone_cli  # lazy: torch (see above)
    return clone_cli.main(argv)


def _partners_crossplay(argv: list) -> int:
    from hrc_partners import crossplay_cli  # lazy: torch, PyBullet (see above)
    return crossplay_cli.main(argv)


def _partners_advisor(argv: list) -> int:
    from hrc_partners import advisor_cli  # lazy: torch, PyBullet (see above)
    return advisor_cli.main(argv)


def _partners_train(argv: list) -> int:
    from hrc_partners import training  # lazy: torch, PyBullet (see above)
    return training.main(argv)


def _partners_train_help(argv: list) -> None:
    from hrc_partners.training_args import build_parser  # lazy: only for --help
    build_parser().parse_args(argv)


def _tree(argv: list) -> int:
    from hrc_agent_node import tree_tool  # lazy: matplotlib for --png (see above)
    return tree_tool.main(argv)


VERBS = (
    Verb(('session',), 'run one session (one case, one seed): the ROS graph, or in one process '
         'with --engine inprocess', 'hrc session --case 2 --seed 0', _session, _session_help),
    Verb(('experiment',), 'run paper cases x seeds (x simulated-human profiles) and report',
         'hrc experiment --cases 2 --seeds 3 --episodes 10', _experiment, _experiment_help),
    Verb(('bag', 'report'), "a session's bags: Table II, the figures, the episode kinds",
         'hrc bag report bags/<session> --out runs/<session>/report', _bag_report),
    Verb(('bag', 'replay'), 'play a recorded episode or session back on the ROS topics',
         'hrc bag replay bags/<session> --rate 2', _bag_replay),
    Verb(('bag', 'info'), 'what a bag holds: files, topics and types, message counts',
         'hrc bag info bags/<session>', bag_info.main),
    Verb(('results',), "the study's results from many sessions: tables, figures, statistics",
         'hrc results runs/<experiment>/bags --out docs', _results, _results_help),
    Verb(('study',), 'subject registry (register), case orders (assign), session commands '
         '(plan), per-subject index (index)', 'hrc study register P07 --consent yes', _study),
    Verb(('operator',), 'pause, resume or abort the running session, or show its status',
         'hrc operator status', _operator),
    Verb(('joystick', 'setup'), 'find the joystick, choose its axis, write its parameter file',
         'hrc joystick setup --list', _joystick_setup),
    Verb(('partners', 'clone'), "train a model of a person's commands from their bags "
         '(behaviour cloning)', 'hrc partners clone bags/<session> --out runs/clone.pt',
         _partners_clone),
    Verb(('partners', 'crossplay'), 'agents x partners (people, clones, populations): who '
         'works with whom', 'hrc partners crossplay --agent a=runs/a.pt --partner '
         'person:paper:0', _partners_crossplay),
    Verb(('partners', 'advisor'), 'which degree of freedom the person should take, from '
         'short trials', 'hrc partners advisor --person person:paper_symmetric:0',
         _partners_advisor),
    Verb(('partners', 'train'), 'train agents with one simulated person or a population',
         'hrc partners train --case 2 --seeds 0 --episodes 50', _partners_train,
         _partners_train_help),
    Verb(('tree',), "the task tree of a case: subtasks, rewards, each training step's roles",
         'hrc tree --case 2', _tree),
)


def take_engine(argv: list) -> tuple:
    """Return (engine, argv without ``--engine``, problems) of ``hrc session``'s arguments."""
    engine, rest, problems = 'graph', [], []
    arguments = iter(argv)
    for argument in arguments:
        if argument == '--':
            rest += [argument, *arguments]
            break
        if argument == '--engine' or argument.startswith('--engine='):
            value = (argument.split('=', 1)[1] if '=' in argument
                     else next(arguments, None))
            if value not in ENGINES:
                problems.append(f'--engine must be one of {", ".join(ENGINES)}, got '
                                f'{value!r}' if value is not None else '--engine needs a value')
            else:
                engine = value
            continue
        rest.append(argument)
    return engine, rest, problems


def study_dir_first(argv: list) -> list:
    """Move ``--study-dir DIR`` before the study's command, where its parser reads it.

    ``hrc study register P07 --study-dir s`` and ``hrc study --study-dir s register P07`` then
    mean the same.
    """
    front, rest = [], []
    arguments = iter(argv)
    for argument in arguments:
        if argument == '--study-dir':
            front += [argument, next(arguments, '')]
        elif argument.startswith('--study-dir='):
            front.append(argument)
        else:
            rest.append(argument)
    return front + rest


def usage(group: str = '') -> str:
    """Return ``hrc --help`` (the verbs, one a line, and the shared flags) or a group's."""
    verbs = [verb for verb in VERBS if not group or verb.words[0] == group]
    width = max(len(verb.name) for verb in verbs)
    lines = [f'usage: {PROG} {group or "<verb>"}{" <verb>" if group else ""} [flags ...]   '
             f'({PROG} {group + " " if group else ""}<verb> --help: its flags and an example)',
             '', 'verbs:']
    for verb in verbs:
        lines += textwrap.wrap(f'  {verb.name:<{width}}  {verb.summary}', width=USAGE_WIDTH,
                               subsequent_indent=' ' * (width + 4))
    if group:
        return '\n'.join(lines)
    lines += ['', 'flags spelled the same by every verb that takes them: --case N, --seed N, '
              '--engine graph|inprocess,', '--human sim|auto|device|joy|model|script, --profile '
              'NAME (simulated human), --set NODE.PARAM=VALUE.',
              'The nodes keep their executables: ros2 run <package> <node> (sim_node, '
              'agent_node, human_node,', 'recorder_node, replay_node, display_node).']
    return '\n'.join(lines)


def refuse(where: str, reasons: list) -> int:
    """Print every reason on stderr, one a line, and return the exit code of bad arguments."""
    prefix = f'{PROG} {where}' if where else PROG
    for reason in reasons:
        print(f'{prefix}: {reason}', file=sys.stderr)
    return EXIT_BAD_ARGUMENTS


def group_help(argv: list) -> str:
    """Return the group of ``hrc <group> --help`` (``hrc bag -h``), else ''."""
    groups = {verb.words[0] for verb in VERBS if len(verb.words) > 1}
    if argv and argv[0] in groups and any(word in ('-h', '--help') for word in argv[1:]):
        if len(argv) < 2 or argv[1].startswith('-'):
            return argv[0]
    return ''


def find_verb(argv: list) -> tuple:
    """Return (verb or None, the rest of argv, the problem if none)."""
    for verb in VERBS:
        if tuple(argv[:len(verb.words)]) == verb.words:
            return verb, argv[len(verb.words):], ''
    words = [word for word in argv[:2] if not word.startswith('-')]
    groups = sorted({verb.words[0] for verb in VERBS if len(verb.words) > 1})
    if words and words[0] in groups:
        choices = [verb.words[1] for verb in VERBS if verb.words[0] == words[0]]
        got = f"'{words[1]}' is not one of them" if len(words) > 1 else 'none given'
        return None, argv, (f"'{words[0]}' needs one of: {', '.join(choices)} ({got}); "
                            f'see {PROG} --help')
    names = [verb.name for verb in VERBS] + groups
    close = difflib.get_close_matches(' '.join(words), names, n=1)
    hint = f" (did you mean '{close[0]}'?)" if close else ''
    return None, argv, (f"unknown verb '{' '.join(words) or argv[0]}'{hint}; the verbs: "
                        f"{', '.join(verb.name for verb in VERBS)}")


def run_verb(verb: Verb, rest: list) -> int:
    """Run the verb; on --help, its help followed by its example."""
    wants_help = any(argument in ('-h', '--help') for argument in rest)
    # argparse names a parser without its own prog after argv[0]: make that the verb.
    program, sys.argv[0] = sys.argv[0], f'{PROG} {verb.name}'
    try:
        if wants_help and verb.help is not None:
            verb.help(list(rest))   # prints the help and exits; returns if '--help' was a value
        code = verb.run(list(rest))
    except SystemExit as exit_:     # argparse's --help and errors
        code = exit_.code if isinstance(exit_.code, int) else (0 if exit_.code is None else 1)
        if exit_.code is not None and not isinstance(exit_.code, int):
            print(exit_.code, file=sys.stderr)
    finally:
        sys.argv[0] = program
    if wants_help and code == 0:
        print(f'\nexample:\n  {verb.example}', flush=True)
    return code or 0


def main(argv=None) -> int:
    """Entry point of ``hrc`` (also ``ros2 run hrc_bringup hrc``)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    verb = None
    try:
        if not argv or argv[0] in ('-h', '--help'):
            print(usage(), file=sys.stdout if argv else sys.stderr, flush=True)
            return 0 if argv else EXIT_BAD_ARGUMENTS
        verb, rest, problem = find_verb(argv)
        if verb is None and group_help(argv):
            print(usage(group_help(argv)), flush=True)
            return 0
        if verb is None:
            return refuse('', [problem])
        return run_verb(verb, rest)
    except KeyboardInterrupt:
        print(f'{PROG} {verb.name if verb else ""}: interrupted', file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:     # `hrc ... | head`: the reader left, nothing to report
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == '__main__':
    sys.exit(main())
