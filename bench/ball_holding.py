#!/usr/bin/env python3
"""Diagnosis: how well a simulated-human profile holds the ball, and its effort on each role.

    python bench/ball_holding.py            # paper, paper_symmetric, skilled at 0.2 s
    python bench/ball_holding.py --profiles paper skilled --seeds 10 --human-period 0.2 0.02
    python bench/ball_holding.py --profiles paper --ablations
    python bench/ball_holding.py --profiles paper --practiced 15   # after 15 episodes

Cases 1, 3 and 5 give the human the rotation and ask it to hold the ball; the robot drives the
slider, which can barely move the ball. Their last training step converges only when the
ball's mean |B_y| per episode is within its tolerance (params/task_tree.yaml, 0.05 m), so the
human's ability to hold the ball bounds them whatever the robot learns.

Two roles, one row per profile and human call period:

* **rotation role** (cases 1/3/5): the profile on the rotation with subtasks [pendulum, ball]
  beside an ideal slider partner (a PD controller holding S_x at 0 with no delay or noise);
  the row gives the mean over seeds of the per-episode mean |B_y| (m) and |P_z| (rad), how
  many episodes satisfy the ball's tolerance, and the person's effort;
* **translation role** (cases 2/4/6): the profile on the translation with subtasks
  [slider, ball] beside an ideal rotation partner (a cascaded PD: ball -> beam angle ->
  torque, no delay or noise); the row gives the person's effort there;
* effort = the variance of the person's normalized command over an episode (the paper's
  human effort), mean over the seeds; ``rot/tr`` is the ratio of the two roles' efforts
  (the paper's human effort of cases 1/3 over cases 2/4 is ~3.7).

``--human-period`` sets how often the person acts (s): the physics runs at that period with
10 ms substeps (PhysicsParams control_period = the human period, substeps = period / 10 ms:
the same integration as the default 0.2 s with 20 substeps), the person is constructed with
``control_period`` = that period, and the ideal partner, standing in for the robot, still
acts every 0.2 s (its command held in between). 0.2 s is today's protocol exactly.

``--ablations`` repeats the rotation role with parts of the person removed (to see what
limits it): no beam-angle noise/bias; also no motor noise and lapses; no delay.
Pure: physics and SimulatedHuman, no ROS.
"""

import argparse
import dataclasses

import numpy as np

from hrc_agent_node.config import share_file, TREE_FILE_NAME
from hrc_agent_node.task_tree import TaskTree
from hrc_joystick_node.human_profile import load_profile
from hrc_joystick_node.sim_human import SimulatedHuman
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

ABLATIONS = {
    'no beam-angle noise/bias': {'pendulum_noise': 0.0, 'pendulum_bias': 0.0},
    'no beam-angle noise/bias, no motor noise, no lapses': {
        'pendulum_noise': 0.0, 'pendulum_bias': 0.0, 'motor_noise': 0.0,
        'motor_noise_floor': 0.0, 'lapse_probability': 0.0},
    'no delay': {'reaction_delay': 0.0},
}
SLIDER_GAIN = 1.0 / 0.05     # normalized push per m of the ideal slider partner
SLIDER_DAMPING = 0.5         # s: its look-ahead on the slider velocity
# The ideal rotation partner (the cascaded PD of hrc_sim_node's test_physics): target beam
# angle per m of ball offset and per m/s of ball speed, push per rad and per rad/s.
ROTATION_BALL_GAIN, ROTATION_BALL_LEAD = 1.0, 0.5
ROTATION_ANGLE_GAIN, ROTATION_RATE_GAIN = 2.0, 1.0
ROBOT_PERIOD = 0.2           # s: the partner (the robot's stand-in) acts this often
SUBSTEP = 0.01               # s: the physics substep at every human period


def ideal_slider(state) -> float:
    """Return the ideal partner's normalized slider command (PD on S_x, no delay, no noise)."""
    push = -SLIDER_GAIN * (state.slider_position + SLIDER_DAMPING * state.slider_velocity)
    return max(-1.0, min(1.0, push))


def ideal_rotation(state) -> float:
    """Return the ideal partner's normalized torque holding the ball (cascaded PD)."""
    target = ROTATION_BALL_GAIN * state.ball_position + ROTATION_BALL_LEAD * state.ball_velocity
    push = (ROTATION_ANGLE_GAIN * (target - state.pendulum_angle)
            - ROTATION_RATE_GAIN * state.pendulum_angular_velocity)
    return max(-1.0, min(1.0, push))


def physics_params_at(human_period: float):
    """Return the physics with a control step of ``human_period`` and 10 ms substeps."""
    substeps = int(round(human_period / SUBSTEP))
    if substeps < 1 or abs(substeps * SUBSTEP - human_period) > 1e-9:
        raise ValueError(f'human period {human_period} s is not a multiple of {SUBSTEP} s')
    if human_period == PhysicsParams().control_period:
        return PhysicsParams()  # today's protocol, bit for bit
    return PhysicsParams(control_period=human_period, substeps=substeps)


def partner_every(human_period: float) -> int:
    """Return after how many person calls the partner acts again (the robot period)."""
    calls = int(round(ROBOT_PERIOD / human_period))
    if calls < 1 or abs(calls * human_period - ROBOT_PERIOD) > 1e-9:
        raise ValueError(f'the robot period {ROBOT_PERIOD} s is not a multiple of the human '
                         f'period {human_period} s')
    return calls


def run_role(profile, role: str, seeds: int, human_period: float, practiced: int = 0) -> dict:
    """Return the mean errors and effort of ``profile`` on ``role`` beside its ideal partner.

    ``role``: 'rotation' (subtasks pendulum and ball, ideal slider partner) or 'translation'
    (subtasks slider and ball, ideal rotation partner).
    """
    params = physics_params_at(human_period)
    every = partner_every(human_period)
    subtasks, partner = ((['pendulum', 'ball'], ideal_slider) if role == 'rotation'
                         else (['slider', 'ball'], ideal_rotation))
    tolerance = ball_tolerance()
    balls, angles, efforts = [], [], []
    with SliderPendulumBall(params) as sim:
        for seed in range(seeds):
            human = SimulatedHuman(profile, role, seed=seed, control_period=human_period,
                                   practiced_episodes=practiced)
            human.reset(0)
            state = sim.reset(seed)
            ball, angle, commands = [], [], []
            partner_command = 0.0
            while not (state.truncated or state.terminated):
                if state.step % every == 0:
                    partner_command = partner(state)
                command = human.act(state, subtasks)
                commands.append(command)
                if role == 'rotation':
                    state = sim.step_normalized(partner_command, command)
                else:
                    state = sim.step_normalized(command, partner_command)
                ball.append(abs(state.ball_position))
                angle.append(abs(state.pendulum_angle))
            balls.append(float(np.mean(ball)))
            angles.append(float(np.mean(angle)))
            efforts.append(float(np.var(commands)))
    return {'ball': float(np.mean(balls)), 'pendulum': float(np.mean(angles)),
            'satisfied': sum(value <= tolerance for value in balls), 'episodes': seeds,
            'effort': float(np.mean(efforts))}


def hold_ball(profile, seeds: int, human_period: float = ROBOT_PERIOD,
              practiced: int = 0) -> dict:
    """Return the mean errors of ``profile`` on the rotation beside the ideal slider."""
    return run_role(profile, 'rotation', seeds, human_period, practiced)


def ball_tolerance() -> float:
    """Return the ball subtask's tolerance (m) from the installed task tree."""
    return TaskTree.from_file(share_file(TREE_FILE_NAME), 'paper').subtasks['ball'].tolerance


def main(argv=None) -> int:
    """Print the table of profiles x human periods (and the ablations on request)."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--profiles', nargs='+', default=['paper', 'paper_symmetric', 'skilled'])
    parser.add_argument('--seeds', type=int, default=6,
                        help='episodes per row, one per seed (initial state and the person)')
    parser.add_argument('--human-period', type=float, nargs='+', default=[ROBOT_PERIOD],
                        help='how often the person acts (s), a divisor of 0.2 s and a '
                        'multiple of 0.01 s; several values give several rows')
    parser.add_argument('--practiced', type=int, default=0,
                        help='episodes the person has practiced before (learning curve; 0: '
                        'the first episode of a new person, the hardest case)')
    parser.add_argument('--ablations', action='store_true',
                        help='also run the rotation role with parts of the person removed')
    args = parser.parse_args(argv)
    problems = [] if args.seeds >= 1 else ['--seeds must be >= 1']
    if args.practiced < 0:
        problems.append('--practiced must be >= 0')
    for period in args.human_period:
        try:
            physics_params_at(period)
            partner_every(period)
        except ValueError as error:
            problems.append(f'--human-period: {error}')
    if problems:
        parser.error('; '.join(problems))
    print(f'ball tolerance {ball_tolerance()} m; {args.seeds} episodes per row; the partner '
          f'acts every {ROBOT_PERIOD} s; the person practiced {args.practiced} episodes before')
    print(f'{"profile":20s} {"period s":>8s} {"|B_y| m":>8s} {"|P_z| rad":>9s} {"within":>7s} '
          f'{"effort rot":>10s} {"effort tr":>9s} {"rot/tr":>6s}')
    for name in args.profiles:
        profile = load_profile(name)
        for period in args.human_period:
            rotation = run_role(profile, 'rotation', args.seeds, period, args.practiced)
            translation = run_role(profile, 'translation', args.seeds, period, args.practiced)
            ratio = rotation['effort'] / translation['effort'] if translation['effort'] else 0.0
            print(f'{name:20s} {period:8.3f} {rotation["ball"]:8.3f} '
                  f'{rotation["pendulum"]:9.3f} '
                  f'{rotation["satisfied"]:3d}/{rotation["episodes"]:<3d} '
                  f'{rotation["effort"]:10.4f} {translation["effort"]:9.4f} {ratio:6.2f}',
                  flush=True)
    if args.ablations:
        print(f'\nablations, rotation role:\n{"profile":20s} {"period s":>8s} {"ablation":52s} '
              f'{"|B_y| m":>8s} {"|P_z| rad":>9s} {"within":>7s}')
        for name in args.profiles:
            profile = load_profile(name)
            for period in args.human_period:
                for ablation, changes in ABLATIONS.items():
                    row = hold_ball(dataclasses.replace(profile, **changes), args.seeds, period,
                                    args.practiced)
                    print(f'{name:20s} {period:8.3f} {ablation:52s} {row["ball"]:8.3f} '
                          f'{row["pendulum"]:9.3f} {row["satisfied"]:3d}/{row["episodes"]:<3d}',
                          flush=True)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
