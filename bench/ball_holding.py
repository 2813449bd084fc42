#!/usr/bin/env python3
"""Diagnosis: how well a simulated-human profile holds the ball when it turns the beam.

    python bench/ball_holding.py            # the profiles paper, paper_symmetric, skilled
    python bench/ball_holding.py --profiles paper --seeds 10

Cases 1, 3 and 5 give the human the rotation and ask it to hold the ball; the robot drives the
slider, which can barely move the ball. Their last training step converges only when the
ball's mean |B_y| per episode is within its tolerance (params/task_tree.yaml, 0.05 m), so the
human's ability to hold the ball bounds them whatever the robot learns. This runs the profile
on the rotation with subtasks [pendulum, ball] beside an ideal slider partner (a PD controller
holding S_x at 0 with no delay or noise) for whole episodes of the default physics, and repeats
it with parts of the person removed (ablations, to see what limits it):

* ``as is``: the profile;
* ``no beam-angle noise/bias``: perfect judgement of the horizontal (pendulum_noise and
  pendulum_bias 0);
* ``no beam-angle noise/bias, no motor noise, no lapses``: only the delay and the ball's
  perception left;
* ``no delay``: reaction_delay 0.

It prints, per row, the mean over seeds of the per-episode mean |B_y| (m), |P_z| (rad) and
how many episodes would satisfy the ball's tolerance. Pure: physics and SimulatedHuman, no ROS.
"""

import argparse
import dataclasses

import numpy as np

ABLATIONS = {
    'as is': {},
    'no beam-angle noise/bias': {'pendulum_noise': 0.0, 'pendulum_bias': 0.0},
    'no beam-angle noise/bias, no motor noise, no lapses': {
        'pendulum_noise': 0.0, 'pendulum_bias': 0.0, 'motor_noise': 0.0,
        'motor_noise_floor': 0.0, 'lapse_probability': 0.0},
    'no delay': {'reaction_delay': 0.0},
}
SLIDER_GAIN = 1.0 / 0.05     # normalized push per m of the ideal slider partner
SLIDER_DAMPING = 0.5         # s: its look-ahead on the slider velocity


def ideal_slider(state) -> float:
    """Return the ideal partner's normalized slider command (PD on S_x, no delay, no noise)."""
    push = -SLIDER_GAIN * (state.slider_position + SLIDER_DAMPING * state.slider_velocity)
    return max(-1.0, min(1.0, push))


def hold_ball(profile, seeds: int) -> dict:
    """Return the mean errors of ``profile`` on the rotation beside the ideal slider."""
    from hrc_joystick_node.sim_human import SimulatedHuman
    from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

    physics_params = PhysicsParams()
    tolerance = ball_tolerance()
    balls, angles = [], []
    with SliderPendulumBall(physics_params) as sim:
        for seed in range(seeds):
            human = SimulatedHuman(profile, 'rotation', seed=seed,
                                   control_period=physics_params.control_period)
            human.reset(0)
            state = sim.reset(seed)
            ball, angle = [], []
            while not (state.truncated or state.terminated):
                command = human.act(state, ['pendulum', 'ball'])
                state = sim.step_normalized(ideal_slider(state), command)
                ball.append(abs(state.ball_position))
                angle.append(abs(state.pendulum_angle))
            balls.append(float(np.mean(ball)))
            angles.append(float(np.mean(angle)))
    return {'ball': float(np.mean(balls)), 'pendulum': float(np.mean(angles)),
            'satisfied': sum(value <= tolerance for value in balls), 'episodes': seeds}


def ball_tolerance() -> float:
    """Return the ball subtask's tolerance (m) from the installed task tree."""
    from hrc_agent_node.config import share_file, TREE_FILE_NAME
    from hrc_agent_node.task_tree import TaskTree

    return TaskTree.from_file(share_file(TREE_FILE_NAME), 'paper').subtasks['ball'].tolerance


def main(argv=None) -> int:
    """Print the table of profiles x ablations."""
    from hrc_joystick_node.sim_human import load_profile

    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--profiles', nargs='+', default=['paper', 'paper_symmetric', 'skilled'])
    parser.add_argument('--seeds', type=int, default=6,
                        help='episodes per row, one per seed (initial state and the person)')
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error('--seeds must be >= 1')
    print(f'ball tolerance {ball_tolerance()} m; {args.seeds} episodes per row')
    print(f'{"profile":16s} {"ablation":52s} {"|B_y| m":>8s} {"|P_z| rad":>9s} {"within":>7s}')
    for name in args.profiles:
        profile = load_profile(name)
        for ablation, changes in ABLATIONS.items():
            row = hold_ball(dataclasses.replace(profile, **changes), args.seeds)
            print(f'{name:16s} {ablation:52s} {row["ball"]:8.3f} {row["pendulum"]:9.3f} '
                  f'{row["satisfied"]:3d}/{row["episodes"]:<3d}', flush=True)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
