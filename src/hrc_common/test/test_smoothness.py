"""Reversals per second: a bang-bang command chatters, a person's corrections do not."""

import math

from hrc_common.smoothness import chatters, HUMAN_REVERSALS_PER_S, reversals, \
    reversals_per_second

PERIOD = 0.2        # s: the control period
STEPS = 200         # a 40 s episode


def test_a_bang_bang_command_chatters():
    # +1, -1, +1, ... at every control step: 199 reversals in 40 s, 4.975 per second
    commands = [1.0 if step % 2 == 0 else -1.0 for step in range(STEPS)]
    rate = reversals_per_second(commands, STEPS * PERIOD)
    assert reversals(commands) == STEPS - 1
    assert rate == 199 / 40 and chatters(rate)


def test_a_slow_correction_does_not():
    # a 0.5 Hz sway at 0.6 of the limit: a reversal every second, 39 in 40 s
    commands = [0.6 * math.sin(2 * math.pi * 0.5 * step * PERIOD + 0.3) for step in range(STEPS)]
    rate = reversals_per_second(commands, STEPS * PERIOD)
    assert rate == 39 / 40 and not chatters(rate)
    assert HUMAN_REVERSALS_PER_S == 2.0


def test_small_commands_around_zero_are_no_direction():
    # a robot holding still with +-0.01 noise (inside the 5% dead band), and 0 between two
    # pushes the same way, reverse nothing
    assert reversals([0.01, -0.01, 0.02, -0.03] * 50) == 0
    assert reversals([0.5, 0.0, 0.0, 0.4, -0.02, 0.6]) == 0
    assert reversals([0.5, 0.0, -0.4]) == 1
    assert reversals_per_second([1.0, -1.0], 0.0) == 0.0
    assert not chatters(math.nan)
