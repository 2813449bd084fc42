#!/usr/bin/env python3
"""Each co-adaptation mechanism of the simulated person, alone, beside a scripted partner.

    python bench/co_adaptation.py --calibrate         # the surprise scales of a smooth partner
    python bench/co_adaptation.py                     # each mechanism alone, then all together
    python bench/co_adaptation.py --mechanism stiffness --role translation --seeds 10
    python bench/co_adaptation.py --replay bags/<experiment>/case2-seed0-paper_co_adapting ...

The person (``paper_co_adapting`` of params/sim_human.yaml, or ``--profile``) plays three
phases of ``--episodes`` episodes each beside a scripted partner on the other degree of
freedom: the partner is smooth (the ideal PD of bench/ball_holding.py), then it explores (the
same PD plus a fresh Gaussian draw of std ``--explore-std`` every 0.2 s, clipped to the limit:
what a stochastic policy's exploration looks like to the person), then it is smooth again.
The rows give, per phase, the mean over seeds and the phase's episodes of the person's
unpredictability ``U`` (1 = as predictable as the smooth partner), stiffness ``K``, bandwidth
``B``, frustration ``F`` (all at the episodes' ends), the person's effort (variance of the
normalized command), the person's stick reversals per second and the ball's mean |B_y| (m).

Each mechanism is measured alone (the profile with the other two mechanisms' rates at 0) and
against the same person without any (``off``) on the same seeds and partner draws, so the
effect printed is the mechanism's: the ``explore/smooth`` ratio of its effort and ball error
with the mechanism, over the same ratio without. What a mechanism must show: it responds to the
exploring partner (its level moves), and it recovers in the last smooth phase.

``--calibrate`` prints the root mean squared prediction error of the person's forward model
beside the smooth partner, per role (the person's mechanisms held inert by the largest scales,
so the person is the paper's): the reference scales of the profile (``slider_surprise_scale``,
``beam_surprise_scale``), measured, not fitted to an outcome.
``--replay`` reads recorded sessions instead: the states of each episode in which the person
acted go through a fresh co-adapting person's internal model (the person's degree of freedom
from the session's status), and it prints the unpredictability U the person met, the median
over their episodes and the first and last five. The recorded states are true states at the
control period (no perception noise), so U there is against the calibration's noisy reference:
a partner the person could not tell from their own perception noise reads about 0.
Pure: PyBullet physics and SimulatedHuman at the default human period 0.02 s, no ROS (the
replay reads MCAP files with hrc_bag).
"""

import argparse
import dataclasses
import statistics

import numpy as np

from ball_holding import ideal_rotation, ideal_slider, partner_every, physics_params_at
from hrc_bag.bag_reader import iter_messages, MessageDecoder, session_files
from hrc_common.dof import ROTATION, TRANSLATION
from hrc_common.smoothness import reversals_per_second
from hrc_joystick_node.co_adaptation import CoAdaptation
from hrc_joystick_node.human_profile import load_profile
from hrc_joystick_node.sim_human import SimulatedHuman
from hrc_sim_node.physics import SliderPendulumBall

HUMAN_PERIOD = 0.02   # s: the default sim.human_period
MECHANISMS = {        # the profile fields that switch each mechanism on
    'stiffness': 'stiffening_rate', 'slowing': 'slowing', 'frustration': 'frustration_rate'}
PHASES = ('smooth', 'explore', 'smooth again')


def alone(profile, mechanism: str):
    """Return ``profile`` with only ``mechanism`` on ('off': none; 'all': as it is)."""
    if mechanism == 'all':
        return profile
    return dataclasses.replace(profile, **{field: 0.0 for name, field in MECHANISMS.items()
                                           if name != mechanism})


def run_phases(profile, role: str, seed: int, episodes: int, explore_std: float) -> list:
    """Return one dict per episode of the three phases for one seed (see the module)."""
    params = physics_params_at(HUMAN_PERIOD)
    every = partner_every(HUMAN_PERIOD)
    subtasks, partner = ((['pendulum', 'ball'], ideal_slider) if role == 'rotation'
                         else (['slider', 'ball'], ideal_rotation))
    human = SimulatedHuman(profile, role, seed=seed, control_period=HUMAN_PERIOD)
    draws = np.random.default_rng([seed, 7])  # the partner's exploration, same with or without
    rows = []
    with SliderPendulumBall(params) as sim:
        for index in range(3 * episodes):
            phase = PHASES[index // episodes]
            human.reset(index)
            state = sim.reset(seed * 1000 + index)
            commands, balls, partner_command = [], [], 0.0
            while not (state.truncated or state.terminated):
                if state.step % every == 0:
                    noise = draws.normal(0.0, explore_std) if phase == 'explore' else 0.0
                    partner_command = max(-1.0, min(1.0, partner(state) + noise))
                command = human.act(state, subtasks)
                commands.append(command)
                state = (sim.step_normalized(partner_command, command) if role == 'rotation'
                         else sim.step_normalized(command, partner_command))
                balls.append(abs(state.ball_position))
            levels = human.co_adaptation
            rows.append({
                'phase': phase, 'effort': float(np.var(commands)), 'ball': float(np.mean(balls)),
                'reversals': reversals_per_second(commands, len(commands) * HUMAN_PERIOD),
                'U': levels.unpredictability if levels else 1.0,
                'K': levels.stiffness if levels else 1.0,
                'B': levels.bandwidth_factor if levels else 1.0,
                'F': levels.frustration if levels else 0.0,
                'rms_error': levels.rms_prediction_error if levels else 0.0})
    return rows


def phase_means(rows: list) -> dict:
    """Return phase -> {quantity: mean over the rows of that phase}."""
    means = {}
    for phase in PHASES:
        chosen = [row for row in rows if row['phase'] == phase]
        means[phase] = {key: statistics.fmean(row[key] for row in chosen)
                        for key in chosen[0] if key != 'phase'}
    return means


def measure(profile, role: str, seeds: int, episodes: int, explore_std: float) -> dict:
    """Return the phase means over ``seeds`` seeds."""
    rows = []
    for seed in range(seeds):
        rows += run_phases(profile, role, seed, episodes, explore_std)
    return phase_means(rows)


def calibrate(profile, seeds: int, episodes: int) -> None:
    """Print the forward model's RMS error beside the smooth partner, per role."""
    print('forward-model prediction error beside the smooth partner (RMS over the episodes)')
    # The largest scales keep the surprise near 0, so no mechanism acts and the person is the
    # paper's while the model's error (independent of the scale) is measured.
    profile = dataclasses.replace(profile, slider_surprise_scale=1e4, beam_surprise_scale=1e4)
    for role, field, unit in (('rotation', 'slider_surprise_scale', 'm/s^2'),
                              ('translation', 'beam_surprise_scale', 'rad/s^2')):
        errors = []
        for seed in range(seeds):
            errors += [row['rms_error'] for row in run_phases(profile, role, seed, episodes, 0.0)
                       if row['phase'] == 'smooth']
        print(f'  person on {role:11s}: {statistics.fmean(errors):.4f} {unit} '
              f'(sd {statistics.pstdev(errors):.4f}) -> {field}')


def stamp_seconds(state) -> float:
    """Return a recorded state's stamp in s."""
    return state.header.stamp.sec + state.header.stamp.nanosec * 1e-9


def replay_unpredictability(profile, folder: str) -> list:
    """Return U per episode the person acted in, replaying a recorded session (see module)."""
    decoder, levels, person_dof, per_episode = MessageDecoder(), None, None, []
    for path in session_files(folder):
        states, involved = [], False
        for message in iter_messages(path, ['/hrc/state', '/hrc/episode', '/hrc/session']):
            decoded = decoder.decode(message)
            if message.topic == '/hrc/state':
                states.append(decoded)
            elif message.topic == '/hrc/episode':
                involved = decoded.human_involved
            elif person_dof is None and decoded.human_dof in (0, 1):
                person_dof = TRANSLATION if decoded.human_dof == 0 else ROTATION
        if not involved or person_dof is None or len(states) < 2:
            continue
        if levels is None:  # the person looks at every state: the states' period, s
            period = stamp_seconds(states[1]) - stamp_seconds(states[0])
            levels = CoAdaptation(profile, person_dof, period)
        levels.start_episode()
        seen = []
        for state in states:
            if levels.partner_dof == TRANSLATION:
                levels.observe(state.slider_position, state.slider_velocity, 0.0)
            else:
                levels.observe(state.pendulum_angle, state.pendulum_angular_velocity, 0.0)
            seen.append(levels.unpredictability)
        per_episode.append(statistics.fmean(seen) if seen else 0.0)
    return per_episode


def print_replays(profile, folders) -> None:
    """Print the replayed unpredictability of each session folder."""
    print('unpredictability U the person met, replayed from the bags (0 = below perception)')
    for folder in folders:
        values = replay_unpredictability(profile, folder)
        if not values:
            print(f'  {folder}: no episode with the person')
            continue
        print(f'  {folder}: {len(values)} episodes with the person, median U '
              f'{statistics.median(values):.2f}; first {[round(v, 1) for v in values[:5]]}, '
              f'last {[round(v, 1) for v in values[-5:]]}')


def print_mechanism(name: str, profile, role: str, args) -> None:
    """Print the phase rows of ``name`` alone and of the same person without co-adaptation."""
    with_it = measure(alone(profile, name), role, args.seeds, args.episodes, args.explore_std)
    without = measure(alone(profile, 'off'), role, args.seeds, args.episodes, args.explore_std)
    print(f'\n{name} (person on {role}), {args.seeds} seeds x {args.episodes} episodes per '
          f'phase, exploration std {args.explore_std}')
    print(f'  {"phase":13s} {"U":>6s} {"K":>5s} {"B":>5s} {"F":>5s} {"effort":>7s} '
          f'{"rev/s":>6s} {"|B_y| m":>8s}   without: {"effort":>7s} {"rev/s":>6s} '
          f'{"|B_y| m":>8s}')
    for phase in PHASES:
        row, base = with_it[phase], without[phase]
        print(f'  {phase:13s} {row["U"]:6.2f} {row["K"]:5.2f} {row["B"]:5.2f} {row["F"]:5.2f} '
              f'{row["effort"]:7.4f} {row["reversals"]:6.2f} {row["ball"]:8.4f}            '
              f'{base["effort"]:7.4f} {base["reversals"]:6.2f} {base["ball"]:8.4f}')
    for key, label in (('effort', 'effort'), ('ball', 'ball error')):
        ratio = with_it['explore'][key] / with_it['smooth'][key]
        base_ratio = without['explore'][key] / without['smooth'][key]
        print(f'  {label} explore/smooth: {ratio:.2f}x with {name}, {base_ratio:.2f}x without '
              f"({ratio / base_ratio:.2f}x the mechanism's own effect)")


def main(argv=None) -> int:
    """Run the calibration or the mechanisms' benches."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--profile', default='paper_co_adapting')
    parser.add_argument('--mechanism', choices=sorted(MECHANISMS) + ['all'], nargs='+',
                        default=sorted(MECHANISMS) + ['all'])
    parser.add_argument('--role', choices=['rotation', 'translation'], default='rotation',
                        help="the person's degree of freedom (rotation: case 5's person)")
    parser.add_argument('--seeds', type=int, default=5)
    parser.add_argument('--episodes', type=int, default=3, help='episodes per phase')
    parser.add_argument('--explore-std', type=float, default=0.5,
                        help="std of the partner's exploration (normalized command)")
    parser.add_argument('--calibrate', action='store_true')
    parser.add_argument('--replay', nargs='+', metavar='SESSION_BAGS',
                        help='recorded session folders to replay through the internal model')
    args = parser.parse_args(argv)
    problems = [text for bad, text in ((args.seeds < 1, '--seeds must be >= 1'),
                                       (args.episodes < 1, '--episodes must be >= 1'),
                                       (args.explore_std < 0, '--explore-std must be >= 0'))
                if bad]
    if problems:
        parser.error('; '.join(problems))
    profile = load_profile(args.profile)
    if args.replay:
        print_replays(profile, args.replay)
        return 0
    if args.calibrate:
        calibrate(profile, args.seeds, args.episodes)
        return 0
    for name in args.mechanism:
        print_mechanism(name, profile, args.role, args)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
