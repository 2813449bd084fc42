#!/usr/bin/env python3
"""Table: the simulated human's delay, motor noise and lapses after N episodes on task.

Every profile of ``params/sim_human.yaml`` acts N episodes of 40 s (199 answered states of
0.2 s, the episode's last state needs no answer) with the profile's declared break between
episodes, through :class:`~hrc_joystick_node.sim_human.SimulatedHuman` itself (simulation
clock). Next to it, what the earlier unbounded model gave (``1 + fatigue_per_minute *
minutes`` with 0.03 / 0.01 / 0.02 per minute for novice / skilled / paper).

Usage: ``python bench/sim_human_fatigue_table.py [--episodes 300]``
(inside the workspace environment: ``source scripts/env.sh``).
"""

import argparse

from hrc_common.paths import params_file
from hrc_joystick_node.human_profile import load_profiles
from hrc_joystick_node.sim_human import SimulatedHuman

REPO_PROFILES = params_file('sim_human.yaml')
CONTROL_PERIOD = 0.2   # s: the sim's control period (params/sim.yaml), the people's call period
OLD_PER_MINUTE = {'novice': 0.03, 'skilled': 0.01, 'paper': 0.02, 'paper_symmetric': 0.02}
ANSWERED_STATES = 199


class _Still:
    """A constant state (fatigue does not depend on what the person sees)."""

    step, time = 0, 0.0
    slider_position, slider_velocity = 0.01, 0.0
    pendulum_angle, pendulum_angular_velocity = 0.05, 0.0
    ball_position, ball_velocity = 0.02, 0.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--episodes', type=int, default=300, help='episodes on task')
    args = parser.parse_args()
    print(f"after {args.episodes} episodes of 40 s on task, each followed by the profile's "
          'break (simulation time)')
    print('| profile | break (s) | delay (s) | x delay | x motor noise | x lapses | '
          'old model: delay (s) | old: x noise |')
    print('|---|---|---|---|---|---|---|---|')
    for name, profile in load_profiles(REPO_PROFILES).items():
        human = SimulatedHuman(profile, 'rotation', seed=0, control_period=CONTROL_PERIOD)
        for episode in range(args.episodes):
            human.reset(episode)
            for _ in range(ANSWERED_STATES):
                human.act(_Still, ['pendulum'])
        fatigue = human.fatigue
        minutes = args.episodes * ANSWERED_STATES * 0.2 / 60.0
        old = 1.0 + OLD_PER_MINUTE.get(name, 0.0) * minutes
        print(f'| {name} | {profile.rest_between_episodes:g} | '
              f'{profile.reaction_delay * fatigue.delay_factor:.3f} | '
              f'{fatigue.delay_factor:.3f} | {fatigue.noise_factor:.3f} | '
              f'{fatigue.lapse_factor:.3f} | {profile.reaction_delay * old:.2f} | {old:.2f} |')


if __name__ == '__main__':
    main()
