"""bench/crossover.py's fit recovers a known crossover loop (the bench validates the person)."""

import importlib.util
import math
import pathlib

import numpy
import pytest

BENCH = pathlib.Path(__file__).resolve().parents[1] / 'bench' / 'crossover.py'


@pytest.fixture(scope='module')
def crossover():
    spec = importlib.util.spec_from_file_location('crossover_bench', BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def known_loop(crossover, gain, delay_steps, remnant_std=0.0):
    """Track the bench's disturbance with an integrator plant and a delayed gain person.

    Plant y' = u (K/s, exact for a held input), person u_p = -gain * y(t - delay); so the open
    loop is gain * e^(-s delay) / s (plus the zero-order hold's half step): crossover = gain.
    """
    period = crossover.PHYSICS_PERIOD
    steps = crossover.RUN_IN_STEPS + crossover.MEASUREMENT_STEPS
    frequencies, amplitudes, phases = crossover.disturbance(0)
    rng = numpy.random.default_rng(0)
    outputs = [0.0] * (delay_steps + 1)
    person, plant = [], []
    for step in range(steps):
        push = float(numpy.sum(amplitudes * numpy.sin(frequencies * step * period + phases)))
        command = -gain * outputs[-1 - delay_steps] + remnant_std * rng.standard_normal()
        total = command + push
        outputs.append(outputs[-1] + period * total)
        if step >= crossover.RUN_IN_STEPS:
            person.append(command)
            plant.append(total)
    return numpy.array(person), numpy.array(plant)


def test_the_fit_recovers_crossover_delay_and_phase_margin(crossover):
    person, plant = known_loop(crossover, gain=3.0, delay_steps=10)  # 3 rad/s, 0.2 s
    fit = crossover.fit_crossover(person, plant)
    # The discrete loop adds about one step (0.02 s) of delay to the 0.2 s.
    assert fit['crossover'] == pytest.approx(3.0, rel=0.05)
    assert fit['delay'] == pytest.approx(0.21, abs=0.015)
    assert fit['phase_margin'] == pytest.approx(90.0 - math.degrees(3.0 * 0.21), abs=3.0)
    assert fit['remnant'] < 0.01  # a linear person: all its output lies on the sines
    assert crossover.in_range('crossover', fit['crossover']) == 'ok'


def test_noise_off_the_sines_is_the_remnant(crossover):
    linear = crossover.fit_crossover(*known_loop(crossover, 3.0, 10))
    noisy = crossover.fit_crossover(*known_loop(crossover, 3.0, 10, remnant_std=0.1))
    assert noisy['remnant'] > 0.1 > 10 * linear['remnant']
    assert noisy['crossover'] == pytest.approx(linear['crossover'], rel=0.1)
