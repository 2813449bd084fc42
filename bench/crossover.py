#!/usr/bin/env python3
"""Validate the simulated person as manual-control research would: the crossover model.

    python bench/crossover.py                     # paper, at 0.2 s and 0.02 s, both DOFs
    python bench/crossover.py --profiles paper skilled novice --person-period 0.02

The person holds its own level-2 subtask (``slider`` on the translation, ``pendulum`` on the
rotation) on the project's physics (``hrc_sim_node.physics``, PyBullet) while a sum-of-sines
disturbance is added to the plant input of that degree of freedom (normalized force or
torque; a compensatory task with zero target). The other degree of freedom is held at 0 by an
ideal PD partner, so its coupling is a small extra disturbance. From the last 81.92 s of a
90 s run (8 s run-in) the bench computes, at the sines' frequencies, the open loop of person
and plant ``L(jw) = -U_person(jw) / U_plant(jw)`` (U_plant = person + disturbance) and fits:

* **crossover frequency** w_c (rad/s): where |L| = 1 (log-log interpolation);
* **phase margin** (deg): 180 + angle L at w_c (interpolated);
* **effective delay** tau_e (s): McRuer's crossover model L = w_c e^(-j w tau_e) / (j w) fitted
  to the phase of L over the sines within [w_c / 3, 3 w_c] (least squares);
* **remnant share**: the part of the person's output variance at frequencies the disturbance
  does not excite (the person's noise and nonlinearity; the linear part lives on the sines).

Why the plants are in the crossover model's range: both are velocity-like (heavy damping), so
at the crossover they behave as K/s: slider: force -> speed with time constant
(m_slider + m_pendulum + m_ball) / slider_damping = 0.16 s; beam: torque -> rate with
hinge_inertia / pendulum_damping = 0.09 s.

Published ranges printed beside the fit (compensatory tracking of K/s-like plants): crossover
2-5 rad/s and effective delay 0.1-0.3 s (McRuer & Jex 1967, IEEE Trans. HFE-8:231, the
crossover model); phase margin 20-60 deg and remnant share 0.1-0.5 are our reading of the
same literature's typical values (a choice of band, not a single cited figure).

The physics steps at 0.02 s (PhysicsParams control_period 0.02 with 2 substeps: the same
10 ms substep as the default 0.2 s with 20), so the disturbance is smooth whatever the person's
period; a person period of 0.2 s holds its command for 10 steps (today's protocol), 0.02 s
acts at every step. The person is practiced (``--practiced`` episodes, default 100: trained
subjects, as tracking experiments use) and seeded. Pure: physics and SimulatedHuman, no ROS.
"""

import argparse
import math

import numpy as np

from hrc_joystick_node.human_profile import load_profile
from hrc_joystick_node.sim_human import SimulatedHuman
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

PHYSICS_PERIOD = 0.02             # s: physics step of the bench (2 substeps of 10 ms)
MEASUREMENT_STEPS = 4096          # 81.92 s: the sines are whole periods of this window
RUN_IN_STEPS = 400                # 8 s before the window (transients, the person settles)
# Sines: integer multiples of the window's base frequency (2 pi / 81.92 s = 0.0767 rad/s),
# primes so that no sine is a harmonic of another; 0.23 to 11.7 rad/s.
SINE_MULTIPLES = (3, 7, 13, 23, 37, 59, 97, 152)
DISTURBANCE_RMS = 0.25            # normalized command (force or torque) of the disturbance
DISTURBANCE_BANDWIDTH = 2.0       # rad/s: the sines' amplitudes roll off above this
RANGES = {'crossover': (2.0, 5.0), 'delay': (0.1, 0.3), 'phase_margin': (20.0, 60.0),
          'remnant': (0.1, 0.5)}
OWN_SUBTASK = {'translation': 'slider', 'rotation': 'pendulum'}


def disturbance(seed: int) -> tuple:
    """Return (frequencies rad/s, amplitudes, phases) of the sum of sines, seeded."""
    base = 2.0 * math.pi / (MEASUREMENT_STEPS * PHYSICS_PERIOD)
    frequencies = base * np.array(SINE_MULTIPLES, dtype=float)
    # A first-order low-pass shape: full amplitude in the band, a fifth at 6x the band, so
    # the high sines still show the person's phase above the noise without dominating.
    amplitudes = 1.0 / np.sqrt(1.0 + (frequencies / DISTURBANCE_BANDWIDTH) ** 2)
    rng = np.random.default_rng([seed, 21])
    phases = rng.uniform(0.0, 2.0 * math.pi, len(frequencies))
    amplitudes *= DISTURBANCE_RMS / math.sqrt(0.5 * float(np.sum(amplitudes ** 2)))
    return frequencies, amplitudes, phases


def partner(dof: str, state) -> float:
    """Return the ideal partner's normalized command holding the other DOF at 0 (PD)."""
    if dof == 'rotation':  # the partner holds the slider
        push = -20.0 * (state.slider_position + 0.5 * state.slider_velocity)
    else:                  # the partner holds the beam level
        push = -2.0 * state.pendulum_angle - 1.0 * state.pendulum_angular_velocity
    return max(-1.0, min(1.0, push))


def track(profile, dof: str, person_period: float, seed: int, practiced: int) -> dict:
    """Run one tracking run; return the person's and the plant's input over the window."""
    every = int(round(person_period / PHYSICS_PERIOD))
    if every < 1 or abs(every * PHYSICS_PERIOD - person_period) > 1e-9:
        raise ValueError(f'person period {person_period} s is not a multiple of '
                         f'{PHYSICS_PERIOD} s')
    steps = RUN_IN_STEPS + MEASUREMENT_STEPS
    params = PhysicsParams(control_period=PHYSICS_PERIOD, substeps=2,
                           episode_duration=steps * PHYSICS_PERIOD)
    frequencies, amplitudes, phases = disturbance(seed)
    human = SimulatedHuman(profile, dof, seed=seed, control_period=person_period,
                           practiced_episodes=practiced)
    human.reset(0)
    person_commands, plant_inputs = [], []
    command = 0.0
    with SliderPendulumBall(params) as sim:
        state = sim.reset(seed)
        for step in range(steps):
            time = step * PHYSICS_PERIOD
            push = float(np.sum(amplitudes * np.sin(frequencies * time + phases)))
            if step % every == 0:
                command = human.act(state, [OWN_SUBTASK[dof]])
            plant = max(-1.0, min(1.0, command + push))
            other = partner(dof, state)
            if dof == 'rotation':
                state = sim.step_normalized(other, plant)
            else:
                state = sim.step_normalized(plant, other)
            if step >= RUN_IN_STEPS:
                person_commands.append(command)
                plant_inputs.append(plant)
    return {'person': np.array(person_commands), 'plant': np.array(plant_inputs),
            'frequencies': frequencies}


def fit_crossover(person: np.ndarray, plant: np.ndarray) -> dict:
    """Return the crossover fit of a run (see the module docstring)."""
    count = len(person)
    person_spectrum = np.fft.rfft(person - person.mean())
    plant_spectrum = np.fft.rfft(plant - plant.mean())
    base = 2.0 * math.pi / (count * PHYSICS_PERIOD)
    bins = np.array(SINE_MULTIPLES)
    frequencies = base * bins
    open_loop = -person_spectrum[bins] / plant_spectrum[bins]
    gain = np.abs(open_loop)
    phase = np.unwrap(np.angle(open_loop))
    # The branch: the lowest sine's phase in (-360, 0] deg (a loop with integral action and
    # lags starts between -90 and -180 deg).
    phase -= 2.0 * math.pi * math.ceil(phase[0] / (2.0 * math.pi))
    crossover, phase_margin = math.nan, math.nan
    for index in range(len(bins) - 1):
        if gain[index] >= 1.0 > gain[index + 1]:
            low, high = math.log(frequencies[index]), math.log(frequencies[index + 1])
            share = math.log(gain[index]) / (math.log(gain[index]) - math.log(gain[index + 1]))
            crossover = math.exp(low + share * (high - low))
            phase_at = phase[index] + share * (phase[index + 1] - phase[index])
            phase_margin = 180.0 + math.degrees(phase_at)
            break
    delay = math.nan
    if math.isfinite(crossover):
        near = (frequencies >= crossover / 3.0) & (frequencies <= 3.0 * crossover)
        # The crossover model's phase: -pi/2 - w tau_e (the integrator, then the delay).
        residual = phase[near] + math.pi / 2.0
        delay = float(-np.sum(frequencies[near] * residual) / np.sum(frequencies[near] ** 2))
    power = np.abs(person_spectrum[1:]) ** 2
    on_sines = np.sum(np.abs(person_spectrum[bins]) ** 2)
    remnant = float(1.0 - on_sines / np.sum(power)) if np.sum(power) > 0 else math.nan
    return {'crossover': crossover, 'phase_margin': phase_margin, 'delay': delay,
            'remnant': remnant, 'gain': gain, 'phase': phase, 'frequencies': frequencies}


def in_range(name: str, value: float) -> str:
    """Return 'ok' when ``value`` lies in the published range of ``name``, else 'OUT'."""
    low, high = RANGES[name]
    return 'ok' if math.isfinite(value) and low <= value <= high else 'OUT'


def main(argv=None) -> int:
    """Print the crossover fit per profile, degree of freedom and person period."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--profiles', nargs='+', default=['paper'])
    parser.add_argument('--person-period', type=float, nargs='+', default=[0.2, 0.02],
                        help='how often the person acts (s), a multiple of 0.02 s')
    parser.add_argument('--seeds', type=int, default=3,
                        help='runs per row (disturbance phases, the person, the start)')
    parser.add_argument('--practiced', type=int, default=100,
                        help='episodes the person has practiced (learning curve)')
    parser.add_argument('--bode', action='store_true', help='also print |L| and angle L')
    args = parser.parse_args(argv)
    problems = [] if args.seeds >= 1 else ['--seeds must be >= 1']
    for period in args.person_period:
        every = round(period / PHYSICS_PERIOD)
        if every < 1 or abs(every * PHYSICS_PERIOD - period) > 1e-9:
            problems.append(f'--person-period {period}: not a multiple of {PHYSICS_PERIOD} s')
    if args.practiced < 0:
        problems.append('--practiced must be >= 0')
    if problems:
        parser.error('; '.join(problems))
    ranges = ', '.join(f'{name} {low:g}-{high:g}' for name, (low, high) in RANGES.items())
    print(f'published ranges: {ranges} (crossover rad/s, delay s, phase margin deg); '
          f'mean of {args.seeds} runs of {MEASUREMENT_STEPS * PHYSICS_PERIOD:.2f} s')
    print(f'{"profile":16s} {"dof":11s} {"period":>6s} {"w_c":>6s} {"":3s} {"tau_e":>6s} '
          f'{"":3s} {"PM deg":>6s} {"":3s} {"remnant":>7s} {"":3s}')
    for name in args.profiles:
        profile = load_profile(name)
        for dof in ('translation', 'rotation'):
            for period in args.person_period:
                fits = [fit_crossover(**{key: run[key] for key in ('person', 'plant')})
                        for run in (track(profile, dof, period, seed, args.practiced)
                                    for seed in range(args.seeds))]
                row = {key: float(np.mean([fit[key] for fit in fits]))
                       for key in ('crossover', 'delay', 'phase_margin', 'remnant')}
                print(f'{name:16s} {dof:11s} {period:6.2f} '
                      f'{row["crossover"]:6.2f} {in_range("crossover", row["crossover"]):3s} '
                      f'{row["delay"]:6.3f} {in_range("delay", row["delay"]):3s} '
                      f'{row["phase_margin"]:6.1f} '
                      f'{in_range("phase_margin", row["phase_margin"]):3s} '
                      f'{row["remnant"]:7.2f} {in_range("remnant", row["remnant"]):3s}',
                      flush=True)
                if args.bode:
                    fit = fits[0]
                    for frequency, gain, phase in zip(fit['frequencies'], fit['gain'],
                                                      fit['phase']):
                        print(f'    w {frequency:6.2f} rad/s  |L| {gain:7.3f}  '
                              f'angle {math.degrees(phase):7.1f} deg')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
