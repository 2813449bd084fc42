"""clone_human: train a human model from recorded sessions (``input: model`` loads it).

    hrc partners clone bags/alice-1 bags/alice-2 bags/alice-3 \
        --held-out alice-3 --out models/alice.pt

Reads every session under the paths, keeps the steps a person drove (joystick, /joy or the
simulated human), holds out the named subjects or sessions (default: the last session, when
there are at least two), trains on the rest and reports the held-out action error and the
response lag (cross-correlation) of the person and of the clone on the held-out episodes.
``--targets applied`` (default) learns from every command the sim applied in each period (one
per slice at the human's own rate, ``TaskState.human_applied``); ``--targets command`` from
the one ``HumanAction`` per step, as before (``hrc_partners.cloning``). On stderr, the
progress with the time left, while the sessions are read (one step a session) and while the
model trains (a line every tenth of the epochs; a bar under them on a terminal, plain lines
when piped).
Exit 2 with every reason for bad input.
"""

import argparse
import json
import pathlib
import sys

from hrc_bag.report import find_sessions
from hrc_common.params import ParameterError
from hrc_common.time_left import TimeLeft
from hrc_joystick_node.human_model import build_network, save_human_model

from hrc_partners.recordings import load_demonstrations


def parse_args(argv):
    """Return the parsed command line."""
    parser = argparse.ArgumentParser(prog='hrc partners clone',
                                     description=__doc__.split('\n\n')[0])
    parser.add_argument('paths', nargs='+', help='session folders or folders of them')
    parser.add_argument('--out', required=True, help='the model file to write (.pt)')
    parser.add_argument('--held-out', nargs='*', default=None, metavar='SUBJECT',
                        help='subjects or session ids to hold out (default: the last session)')
    parser.add_argument('--dof', choices=['translation', 'rotation'], default=None,
                        help='the degree of freedom to clone (needed when both were driven)')
    parser.add_argument('--history-steps', type=int, default=6,
                        help='states of history the model sees (>= 1)')
    parser.add_argument('--hidden', type=int, nargs='+', default=[32, 32],
                        help="widths of the network's hidden layers")
    parser.add_argument('--epochs', type=int, default=600, help='training epochs')
    parser.add_argument('--seed', type=int, default=0, help='seed of the training')
    parser.add_argument('--targets', choices=['applied', 'command'], default='applied',
                        help='learn from the commands the sim applied in each period (one per '
                        "slice at the human's rate) or from the HumanAction of each step")
    parser.add_argument('--json', action='store_true', help='print the report as JSON')
    return parser.parse_args(argv)


PROGRESS_LINES = 10        # lines of training progress (one every tenth of the epochs)


def load_with_progress(paths, log, stream=None) -> list:
    """Return ``load_demonstrations(paths)``, read one session folder at a time with progress."""
    folders = find_sessions(paths)
    progress = TimeLeft(len(folders), 'sessions', stream=stream or sys.stderr)
    demonstrations = []
    for done, folder in enumerate(folders, start=1):
        loaded = load_demonstrations([folder], log)
        demonstrations += loaded
        steps = sum(item.steps for item in loaded)
        progress.show(done, f'clone_human: read {folder.name} ({steps} driven steps)')
    progress.close()
    return demonstrations


def epoch_progress(epochs: int, stream=None):
    """Return ``(on_epoch, progress)``: ``on_epoch(done)`` shows the training's time left.

    A line every tenth of the epochs (and at the last), so that neither a terminal nor a log
    is flooded; on a terminal the bar under them is redrawn with each.
    """
    progress = TimeLeft(epochs, 'epochs', stream=stream or sys.stderr)
    every = max(1, epochs // PROGRESS_LINES)

    def on_epoch(done):
        if done == 0:   # the epochs start: the time spent building the data set is no epoch's
            progress.started = progress.clock()
        elif done % every == 0 or done == epochs:
            progress.show(done, 'clone_human: training')
    return on_epoch, progress


def clone(args, log=print) -> dict:
    """Train and save the clone described by ``args``; return the report (ParameterError)."""
    from hrc_partners import cloning  # lazy: torch (seconds): --help answers without it

    problems = []
    if not 1 <= args.history_steps <= 256:
        problems.append(f'--history-steps: expected 1..256, got {args.history_steps}')
    if args.epochs < 1:
        problems.append(f'--epochs: expected >= 1, got {args.epochs}')
    if any(width < 1 for width in args.hidden):
        problems.append(f'--hidden: widths must be >= 1, got {args.hidden}')
    if not pathlib.Path(args.out).parent.is_dir():
        problems.append(f'--out: no folder {pathlib.Path(args.out).parent}')
    missing = [path for path in args.paths if not pathlib.Path(path).exists()]
    problems += [f'{path}: no such session folder' for path in missing]
    if problems:
        raise ParameterError('; '.join(problems), problems)
    demonstrations = load_with_progress(args.paths, log)
    dofs = sorted({item.dof for item in demonstrations})
    if not demonstrations:
        raise ParameterError('no session under the paths has a step driven by a person')
    if args.dof is None and len(dofs) > 1:
        raise ParameterError(f'the person drove {dofs}: choose one with --dof')
    dof = args.dof or dofs[0]
    demonstrations = [item for item in demonstrations if item.dof == dof]
    if not demonstrations:
        raise ParameterError(f'no session in which a person drove {dof}')
    subjects = sorted({item.subject for item in demonstrations})
    held_out = args.held_out
    if held_out is None:
        held_out = [demonstrations[-1].session_id] if len(demonstrations) > 1 else []
    unknown = [name for name in held_out if name not in subjects
               and name not in {item.session_id for item in demonstrations}]
    if unknown:
        raise ParameterError(f'--held-out: unknown subjects or sessions {unknown}; known '
                             f'subjects {subjects}')
    train, test = cloning.split_by_subject(demonstrations, held_out)
    if not train:
        raise ParameterError('every session is held out: nothing left to train on')
    settings = cloning.CloneSettings(history_steps=args.history_steps,
                                     hidden=tuple(args.hidden), epochs=args.epochs,
                                     seed=args.seed, targets=args.targets)
    on_epoch, progress = epoch_progress(settings.epochs)
    try:
        config, state_dict, train_rmse = cloning.train_clone(train, settings, on_epoch)
    finally:
        progress.close()
    period = train[0].control_period
    config.update(dof=dof, control_period=period, description=(
        f'cloned on {dof} from {", ".join(item.session_id for item in train)} (sources: '
        f'{", ".join(sorted({s for item in train for s in item.sources}))})'))
    save_human_model(args.out, config, state_dict)
    report = {'model': str(args.out), 'dof': dof, 'control_period': period,
              'targets': settings.targets,
              'training_sessions': [item.session_id for item in train],
              'held_out_sessions': [item.session_id for item in test],
              'training_steps': sum(item.steps for item in train),
              'training_rmse': train_rmse}
    if test:
        network = build_network(config)
        network.load_state_dict(state_dict)
        error = cloning.action_error(network, test, settings.history_steps, settings.targets)
        traces = [trace for item in test for trace in item.episodes]
        report['held_out'] = {
            'steps': error.steps, 'rmse': error.rmse, 'mae': error.mae,
            'zero_command_rmse': error.zero_rmse, 'correlation': error.correlation,
            # the person's commands as learned: per step the mean of what was applied
            'person_lag_s': cloning.response_lag(
                traces, [cloning.period_commands(t, settings.targets) for t in traces], dof,
                period),
            'clone_lag_s': cloning.response_lag(
                traces, [cloning.predict(network, t, settings.history_steps) for t in traces],
                dof, period)}
    return report


def describe(report: dict) -> str:
    """Return the report as readable lines."""
    lines = [f'clone_human: {report["model"]} ({report["dof"]}, {report["control_period"]} s)',
             f'  trained on {len(report["training_sessions"])} sessions '
             f'({report["training_steps"]} driven steps): {", ".join(report["training_sessions"])}'
             f'; training RMSE {report["training_rmse"]:.4f}; learned from the '
             + ('commands applied in each period' if report.get('targets') == 'applied'
                else 'HumanAction of each step')]
    held = report.get('held_out')
    if held is None:
        lines.append('  no held-out session: no held-out error (give at least two sessions)')
    else:
        lines.append(f'  held out {", ".join(report["held_out_sessions"])} ({held["steps"]} '
                     f'steps): action RMSE {held["rmse"]:.4f} (always 0: '
                     f'{held["zero_command_rmse"]:.4f}), MAE {held["mae"]:.4f}, correlation '
                     f'{held["correlation"]:.3f}')
        lines.append(f'  response lag (cross-correlation, held-out episodes): person '
                     f'{held["person_lag_s"]:.3f} s, clone {held["clone_lag_s"]:.3f} s')
    return '\n'.join(lines)


def main(argv=None) -> int:
    """Console entry point."""
    args = parse_args(argv)
    try:
        report = clone(args, log=lambda line: print(f'clone_human: {line}', file=sys.stderr))
    except ParameterError as error:
        for reason in (error.reasons if getattr(error, 'reasons', None) else [str(error)]):
            print(f'clone_human: {reason}', file=sys.stderr)
        return 2
    except (FileNotFoundError, ValueError) as error:
        print(f'clone_human: {error}', file=sys.stderr)
        return 2
    print(json.dumps(report, indent=2) if args.json else describe(report))
    return 0


if __name__ == '__main__':
    sys.exit(main())
