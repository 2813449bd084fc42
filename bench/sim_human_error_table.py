#!/usr/bin/env python3
"""Table: the error each simulated-human profile reaches holding each degree of freedom alone.

For every profile of ``params/sim_human.yaml`` and each degree of freedom, the simulated human
holds its own level-2 subtask (translation: the slider, rotation: the pendulum) on the physics
core while the robot does nothing; next to it, zero action on the same initial states. Also:
the rotation actor asked to hold the ball too (level-guided step 2), and the person after
practice. Errors are mean |S_x| (m), |P_z| (rad), |B_y| (m) over each episode, averaged over
the episodes; effort is the variance of the normalized command in the first episode (the
paper's Table II measure).

Usage: ``python bench/sim_human_error_table.py [--episodes 20] [--seed 0]``
(run inside the workspace environment: ``source scripts/env.sh``).
"""

import argparse
import time

import numpy

from hrc_joystick_node.evaluation import human_episode, run_episode
from hrc_common.paths import params_file
from hrc_joystick_node.human_profile import load_profiles
from hrc_joystick_node.sim_human import SimulatedHuman
from hrc_sim_node.physics import SliderPendulumBall

REPO_PROFILES = params_file('sim_human.yaml')
CONTROL_PERIOD = 0.2   # s: the sim's control period (params/sim.yaml), the people's call period
CASES = [  # (label, degree of freedom, subtasks, subtask whose error is reported)
    ('translation: slider', 'translation', ['slider'], 'slider'),
    ('rotation: pendulum', 'rotation', ['pendulum'], 'pendulum'),
    ('rotation: pendulum+ball', 'rotation', ['pendulum', 'ball'], 'ball'),
]
UNITS = {'slider': 'm', 'pendulum': 'rad', 'ball': 'm'}


def measure(physics, profile, dof, subtasks, episodes, seed, practiced):
    """Return (mean errors dict, mean effort) over ``episodes`` first episodes of new people."""
    errors, efforts = [], []
    for index in range(episodes):
        # Person `index` in their first episode (after `practiced` earlier ones).
        human = SimulatedHuman(profile, dof, seed=seed + index, practiced_episodes=practiced,
                               control_period=CONTROL_PERIOD)
        result = human_episode(physics, human, practiced, seed + index, subtasks)
        errors.append(result.errors)
        efforts.append(result.effort)
    mean = {key: float(numpy.mean([e[key] for e in errors])) for key in errors[0]}
    return mean, float(numpy.mean(efforts))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--episodes', type=int, default=20, help='episodes (people) per cell')
    parser.add_argument('--seed', type=int, default=0, help='first seed (initial state, person)')
    parser.add_argument('--practiced', type=int, default=20,
                        help='episodes of practice for the "trained" column')
    parser.add_argument('--profiles', default=None,
                        help='profiles YAML (default: the repo params/sim_human.yaml)')
    args = parser.parse_args()
    path = args.profiles or (REPO_PROFILES if REPO_PROFILES.exists() else None)
    profiles = load_profiles(path)
    physics = SliderPendulumBall()
    start = time.monotonic()
    print(f'{args.episodes} episodes of 40 s per cell, seeds {args.seed}..'
          f'{args.seed + args.episodes - 1}; robot idle; error = mean |x| over the episode')
    print()
    header = (f'| {"holding":<24} | {"profile":<8} | {"zero action":>11} | {"first episode":>13} '
              f'| {"after " + str(args.practiced) + " ep.":>12} | {"effort, 1st ep.":>15} |')
    print(header)
    print('|' + '|'.join('-' * (len(cell)) for cell in header.split('|')[1:-1]) + '|')
    for label, dof, subtasks, reported in CASES:
        zero = [run_episode(physics, dof, args.seed + index).errors[reported]
                for index in range(args.episodes)]
        zero_error = float(numpy.mean(zero))
        for name, profile in profiles.items():
            first, effort = measure(physics, profile, dof, subtasks, args.episodes, args.seed, 0)
            trained, _ = measure(physics, profile, dof, subtasks, args.episodes, args.seed,
                                 args.practiced)
            unit = UNITS[reported]
            print(f'| {label:<24} | {name:<8} | {zero_error:>7.4f} {unit:<3} '
                  f'| {first[reported]:>9.4f} {unit:<3} | {trained[reported]:>8.4f} {unit:<3} '
                  f'| {effort:>15.4f} |')
    physics.close()
    print(f'\n({time.monotonic() - start:.1f} s)')


if __name__ == '__main__':
    main()
