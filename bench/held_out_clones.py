#!/usr/bin/env python3
"""Cloned people for the held-out protocol: record a person, clone them on each degree of freedom.

The held-out partners of ``bench/held_out_partners.py`` are simulated people with one trait
outside the training population. A lab's held-out partners would also be people cloned from
their recordings (ZSC-Eval's held-out partners include behaviour-cloned humans): a clone is a
learned policy, not the parametric model the training population is drawn from, so it tests
the robot against behaviour of another form. This bench makes such partners from the
in-process engine's real bags:

1. records ``--sessions`` short sessions of the simulated person ``--person`` (a profile of
   ``params/sim_human.yaml``; default ``novice``, which the ``paper`` population is not drawn
   from) in case 5 (the person on the rotation from the first episode) and case 6 (on the
   translation), ``--episodes`` of 40 s each, the person acting at the sim's 0.02 s;
2. clones one model per degree of freedom with ``hrc partners clone`` (the last session held
   out, its action error and response lag printed), to ``OUT/<person>-rotation.pt`` and
   ``OUT/<person>-translation.pt``.

Then::

    python bench/held_out_partners.py runs/pf-sac --oracles oracles.json --train-oracles \
        --clone novice=OUT/novice-rotation.pt --clone novice=OUT/novice-translation.pt

A modelling choice, not a fact: the person is simulated (no one's real recordings are here),
and the clone is deterministic (their mean response), so it is steadier than they are
(docs/partners.md, section 1).
"""

import argparse
import pathlib
import sys
import tempfile

from hrc_common.paths import params_dir
from hrc_joystick_node.human_profile import load_profile
from hrc_partners import clone_cli, synthetic

HUMAN_DOF_CASE = {'rotation': 5, 'translation': 6}   # together from the first episode
EPISODE_SECONDS = 40.0                               # the paper's episode
HUMAN_PERIOD = 0.02                                  # s: the sim's default human rate


def parse_arguments(argv) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--person', default='novice',
                        help='the profile of params/sim_human.yaml to record (default novice)')
    parser.add_argument('--sessions', type=int, default=3,
                        help='sessions recorded per degree of freedom (seeds 0..N-1; >= 2)')
    parser.add_argument('--episodes', type=int, default=4, help='episodes per session')
    parser.add_argument('--epochs', type=int, default=600, help="the clone's training epochs")
    parser.add_argument('--out', type=pathlib.Path, required=True,
                        help='the folder the clones are written to')
    parser.add_argument('--keep-bags', type=pathlib.Path,
                        help='record into this folder and keep the bags (default: a scratch one)')
    return parser.parse_args(argv)


def argument_problems(args) -> list:
    """Return every reason the arguments cannot run (all at once)."""
    problems = []
    try:
        load_profile(args.person)
    except (ValueError, KeyError, OSError) as error:
        problems.append(f'--person {args.person}: {error}')
    if args.sessions < 2:
        problems.append('--sessions must be >= 2 (one is held out)')
    if min(args.episodes, args.epochs) < 1:
        problems.append('--episodes and --epochs must be >= 1')
    if not args.out.is_dir():
        problems.append(f'--out {args.out}: no such folder')
    return problems


def record_and_clone(args, scratch: pathlib.Path) -> int:
    """Record the person on each degree of freedom and clone them; return the exit code."""
    for dof, case in HUMAN_DOF_CASE.items():
        print(f'held_out_clones: recording {args.person} on the {dof} (case {case}, '
              f'{args.sessions} sessions of {args.episodes} episodes)', flush=True)
        folders = synthetic.record_sessions(
            scratch / f'bags-{dof}', scratch / f'runs-{dof}',
            str(params_dir() / 'sim_human.yaml'), [args.person], range(args.sessions),
            case=case, episodes=args.episodes, seconds=EPISODE_SECONDS,
            human_period=HUMAN_PERIOD)
        code = clone_cli.main([*folders, '--dof', dof, '--epochs', str(args.epochs),
                               '--out', str(args.out / f'{args.person}-{dof}.pt')])
        if code:
            return code
    return 0


def main(argv=None) -> int:
    args = parse_arguments(argv)
    problems = argument_problems(args)
    if problems:
        print('held_out_clones: ' + '; '.join(problems), file=sys.stderr)
        return 2
    if args.keep_bags is not None:
        args.keep_bags.mkdir(parents=True, exist_ok=True)
        return record_and_clone(args, args.keep_bags)
    with tempfile.TemporaryDirectory(prefix='held-out-clones-') as scratch:
        return record_and_clone(args, pathlib.Path(scratch))


if __name__ == '__main__':
    sys.exit(main())
