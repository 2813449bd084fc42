"""role_advisor: calibrate a (simulated) person on each DOF and recommend who drives what.

    hrc partners advisor --person person:paper_symmetric:4 --weak rotation:3 \
        --robot-rotation runs/partners/c2-population-s0.pt \
        --robot-translation runs/partners/c1-population-s0.pt

The person: ``profile:NAME`` or ``person:NAME:K`` (a simulated person; ``--weak DOF:FACTOR``
makes them FACTOR times worse at judging that DOF's quantity) -- a person at the joystick
would be calibrated through the live session instead (not wired here). The robots: a trained
agent that drives the rotation (``--robot-rotation``, for the person on the translation, e.g.
a case-2 checkpoint) and one that drives the translation (``--robot-translation``, e.g. case
1), or ``--stand-in-robot NOISE``: the scripted PD controller with command noise standing in
for both (said in the output). ``--validate N`` runs the validation on N simulated people with
known asymmetric skills instead (stand-in robot). Exit 2 with every reason for bad input.
"""

import argparse
import pathlib
import sys

from hrc_joystick_node.population import sample_person
from hrc_joystick_node.human_profile import load_profile


def main(argv=None) -> int:
    """Console entry point."""
    parser = argparse.ArgumentParser(prog='hrc partners advisor',
                                     description=__doc__.split('\n\n')[0])
    parser.add_argument('--person', default='person:paper_symmetric:0',
                        help='the simulated person: profile:NAME or person:NAME:K')
    parser.add_argument('--weak', default='', metavar='DOF:FACTOR',
                        help="make the person FACTOR times worse at judging that DOF's quantity")
    parser.add_argument('--robot-rotation', default='', metavar='CHECKPOINT',
                        help='agent that drives the rotation (e.g. a case-2 checkpoint)')
    parser.add_argument('--robot-translation', default='', metavar='CHECKPOINT',
                        help='agent that drives the translation (e.g. a case-1 checkpoint)')
    parser.add_argument('--stand-in-robot', type=float, default=None, metavar='NOISE',
                        help='a scripted PD robot with this command noise for both DOFs '
                             'instead of the checkpoints')
    parser.add_argument('--episodes', type=int, default=5, help='episodes per DOF')
    parser.add_argument('--seconds', type=float, default=12.0, help='s per episode')
    parser.add_argument('--rest', type=float, default=5.0, help='s between episodes')
    parser.add_argument('--seed', type=int, default=0, help='seed of the person and the robots')
    parser.add_argument('--validate', type=int, default=0, metavar='N',
                        help='validate the advisor on N simulated people of known skills instead')
    parser.add_argument('--truth-seconds', type=float, default=0.0,
                        help="with --validate: s per episode of the truth's runs (0: --seconds)")
    args = parser.parse_args(argv)

    # after the parsing: these load torch (seconds), --help and usage errors answer without
    from hrc_partners import advisor  # lazy: torch (seconds), see above
    from hrc_engine.partners import spec_problem  # lazy: torch, as above

    problems = []
    if args.episodes < 2:
        problems.append(f'--episodes: expected >= 2 (an interval needs two), got {args.episodes}')
    if not 1.0 <= args.seconds <= 120.0:
        problems.append(f'--seconds: expected 1..120, got {args.seconds}')
    if args.rest < 0:
        problems.append(f'--rest: expected >= 0, got {args.rest}')
    kind = args.person.partition(':')[0]
    if kind not in ('profile', 'person') or spec_problem(args.person):
        problems.append(f'--person {args.person!r}: expected profile:NAME or person:NAME:K')
    weak_dof, _, factor = args.weak.partition(':')
    if args.weak and (weak_dof not in advisor.DOFS or not _positive(factor)):
        problems.append(f'--weak {args.weak!r}: expected translation:FACTOR or '
                        f'rotation:FACTOR with FACTOR > 0')
    if args.stand_in_robot is None and not args.validate:
        for name, path in (('--robot-rotation', args.robot_rotation),
                           ('--robot-translation', args.robot_translation)):
            if not path:
                problems.append(f'{name}: a checkpoint is needed (or --stand-in-robot NOISE)')
            elif not pathlib.Path(path).is_file():
                problems.append(f'{name}: no such checkpoint {path}')
    if problems:
        for problem in problems:
            print(f'role_advisor: {problem}', file=sys.stderr)
        return 2
    plan = advisor.CalibrationPlan(args.episodes, args.seconds, args.rest, args.seed)
    if args.validate:
        results = advisor.validate(args.validate, plan, robot_noise=args.stand_in_robot or 1.0,
                                   seed=args.seed, truth_seconds=args.truth_seconds)
        print(advisor.validation_table(results))
        return 0
    try:
        person = _person(args.person, weak_dof if args.weak else '', factor)
        robots = _robots(args, advisor)
    except (ValueError, OSError) as error:
        print(f'role_advisor: {error}', file=sys.stderr)
        return 2
    advice = advisor.calibrate(advisor.simulated_person(person, args.seed), robots, plan)
    print(advice.describe())
    return 0


def _positive(text: str) -> bool:
    try:
        return float(text) > 0
    except ValueError:
        return False


def _person(spec: str, weak_dof: str, factor: str):
    from hrc_partners.advisor import weaken  # lazy: torch (via partners), as in main()
    from hrc_engine.partners import parse_spec  # lazy: torch, as above

    parsed = parse_spec(spec)
    person = load_profile(parsed.name)
    if parsed.kind == 'person':
        person = sample_person(person, parsed.person)
    return weaken(person, weak_dof, float(factor)) if weak_dof else person


def _robots(args, advisor):
    if args.stand_in_robot is not None:
        return {dof: advisor.ScriptedRobot(advisor.other_dof(dof), noise=args.stand_in_robot,
                                           seed=args.seed) for dof in advisor.DOFS}
    robots = {'translation': advisor.TrainedRobot(args.robot_rotation, args.seed),
              'rotation': advisor.TrainedRobot(args.robot_translation, args.seed)}
    for person_dof, robot in robots.items():
        if robot.dof != advisor.other_dof(person_dof):
            raise ValueError(f'the robot for the person on {person_dof} must drive '
                             f'{advisor.other_dof(person_dof)}, but its checkpoint drives '
                             f'{robot.dof}')
    return robots


if __name__ == '__main__':
    sys.exit(main())
