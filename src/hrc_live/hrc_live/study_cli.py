"""The study's command line: register subjects, assign case orders, plan sessions, list the index.

    hrc study register P07 --consent yes            # consent dated today
    hrc study assign                                 # Williams square over 1..6
    hrc study assign --cases 1 2 5                   # the researcher's set
    hrc study plan P07                               # the session commands
    hrc study index                                  # sessions per subject

Everything lives in ``--study-dir`` (default ``study``): ``subjects.yaml`` and ``index.yaml``,
mode 0600 (hrc_live.study). Exit codes: 0 done, 2 bad usage or a rejected entry (every reason
printed).
"""

import argparse
import datetime
import pathlib
import shlex
import sys

from hrc_live.study import (assign_orders, by_subject, consent_problem, load_index,
                            load_registry, PAPER_CASES, register, StudyError,
                            update_registry)
from hrc_common.paths import params_dir
from hrc_common.session_plan import DEFAULT_LEARNING, learning_names


def parse_args(argv=None):
    """Parse the command line."""
    parser = argparse.ArgumentParser(prog='hrc study', description='Pseudonymous subject '
                                     'registry, counterbalanced case orders and the '
                                     'per-subject session index of an hrc study (no names are '
                                     'stored).')
    parser.add_argument('--study-dir', default='study', help='folder of the study files')
    commands = parser.add_subparsers(dest='command', required=True)
    add = commands.add_parser('register', help='add a subject or record a new consent answer')
    add.add_argument('subject_id', help='the pseudonym (e.g. P07), never a name')
    add.add_argument('--consent', required=True, choices=('yes', 'no'),
                     help='the consent answer the subject gave')
    add.add_argument('--date', default=None, help='date of the consent answer (default today)')
    assign = commands.add_parser('assign', help='give consenting subjects their case order')
    assign.add_argument('--cases', type=int, nargs='+', default=list(PAPER_CASES),
                        help='the cases to counterbalance (default 1..6)')
    plan = commands.add_parser('plan', help="print the commands of a subject's sessions")
    plan.add_argument('subject_id', help='a registered subject')
    plan.add_argument('--practice', type=int, default=3,
                      help='practice episodes before each condition (default 3; 0 = none)')
    plan.add_argument('--human', default='device', choices=('device', 'joy'),
                      help='the joystick as a device (default) or through a joy node')
    plan.add_argument('--learning', default=DEFAULT_LEARNING, metavar='NAME',
                      help='learning configuration of every condition (params/learning/'
                      f'<name>.yaml; default {DEFAULT_LEARNING}, the one the simulated study '
                      "measured best for the person's time)")
    plan.add_argument('--joystick-params', default='joystick.yaml', metavar='FILE',
                      help='the joystick parameters file of "hrc joystick setup", read by '
                      'each session (default joystick.yaml; --human device)')
    plan.add_argument('--episodes', type=int, default=0, metavar='N',
                      help='at most N training episodes per condition (default: the learning '
                      'configuration)')
    commands.add_parser('index', help='list the sessions per subject')
    return parser.parse_args(argv)


def plan_commands(subject, study_dir: str, practice: int, human: str,
                  learning: str = DEFAULT_LEARNING, joystick_params: str = '',
                  episodes: int = 0) -> list:
    """Return the session command lines of ``subject``'s conditions, in order.

    Each names its learning configuration (``--learning``), the same in every condition, so
    the plan says what the robot runs and the live study runs what a simulated one predicts;
    with a device, the joystick parameters file (its axis, inversion, deadzone), said in a
    comment when it does not exist yet.
    """
    lines = []
    if joystick_params and human == 'device' and not pathlib.Path(joystick_params).is_file():
        lines.append(f'# {joystick_params} does not exist yet: run "hrc joystick setup -o '
                     f'{joystick_params}" with the subject\'s joystick first')
    for position, case in enumerate(subject.order, start=1):
        command = ['hrc', 'session', '--case', str(case), '--mode', 'realtime', '--human',
                   human, '--display', '--tlx', '--subject-id', subject.id, '--study-dir',
                   study_dir]
        if joystick_params and human == 'device':
            command += ['--params', joystick_params]
        if practice:
            command += ['--practice', str(practice)]
        if episodes:
            command += ['--episodes', str(episodes)]
        command += ['--learning', learning]
        lines.append(f'# condition {position} of {len(subject.order)}: case {case}')
        lines.append(shlex.join(command))
    return lines


def index_line(entry) -> str:
    """Return the line of ``study index`` for one entry (its attempts when it has several)."""
    codes = [str(attempt['exit_code']) for attempt in entry.attempts]
    return (f'  {entry.started}  {entry.kind:9s} case {entry.case} (position {entry.position})'
            f'  {entry.session_id}  exit {entry.exit_code}'
            + (f" (attempts: exit {', '.join(codes)})" if len(codes) > 1 else '')
            + (f'  TLX {entry.tlx_file}' if entry.tlx_file else ''))


def main(argv=None) -> int:
    """Entry point of ``hrc study``."""
    options = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        subjects = load_registry(options.study_dir)
        if options.command == 'register':
            date = options.date or datetime.date.today().isoformat()
            (subject, count), path = update_registry(options.study_dir, lambda subjects: (
                register(subjects, options.subject_id, options.consent, date), len(subjects)))
            print(f'{subject.id}: consent {subject.consent} ({subject.consent_date}); '
                  f'registry {path} ({count} subjects)')
        elif options.command == 'assign':
            assigned, _ = update_registry(options.study_dir, lambda subjects: assign_orders(
                subjects, options.cases))
            for subject in assigned:
                print(f'{subject.id}: cases in the order {subject.order}')
            if not assigned:
                print('nobody to assign (every consenting subject has an order)')
        elif options.command == 'plan':
            problem = consent_problem(subjects, options.subject_id)
            if problem:
                raise StudyError(problem)
            if options.learning not in learning_names(params_dir()):
                raise StudyError(f'--learning {options.learning!r}: not a learning '
                                 'configuration (there are: '
                                 f'{", ".join(learning_names(params_dir()))})')
            subject = next(s for s in subjects if s.id == options.subject_id)
            if not subject.order:
                raise StudyError(f'{subject.id} has no case order yet: run "study assign"')
            if options.episodes < 0:
                raise StudyError(f"--episodes must be >= 1 (0: the learning configuration's), "
                                 f'got {options.episodes}')
            print('\n'.join(plan_commands(subject, options.study_dir, options.practice,
                                          options.human, options.learning,
                                          options.joystick_params, options.episodes)))
        else:
            for subject_id, entries in by_subject(load_index(options.study_dir)).items():
                print(f'{subject_id}:')
                for entry in entries:
                    print(index_line(entry))
    except StudyError as error:
        print(f'study: {error}', file=sys.stderr)
        return 2
    return 0


if __name__ == '__main__':
    sys.exit(main())
