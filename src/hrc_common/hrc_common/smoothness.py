"""How smooth an actor's commands are: reversals of direction per second. Pure.

A command *reverses* when its sign changes between two commands outside the dead band (a
command within :data:`DEAD_BAND` of zero, in units of the actor's limit, is no direction: the
stick at rest, a robot holding still). The rate is reversals per second of the episode.

**The threshold, from human movement.** People controlling an unstable load correct
intermittently, about 2 corrections per second, with little coherence above 1-2 Hz (Loram et
al. 2011; ``DESIGN.md``, facts for the person in the loop). A correction reverses the command
at most once, so a human-like actor reverses at most about :data:`HUMAN_REVERSALS_PER_S` = 2
times per second; the 0.2 s control period allows 5. An actor above it **chatters**: it
switches direction faster than a person corrects (a bang-bang policy at about +-1 reverses
up to 5 times per second). Fact: the correction rate. Choice: one reversal per correction and
the dead band of 5% of the limit.

The rate goes with the actor's effort (the variance of its normalized command, Table II): a
policy that reverses often at a large effort is the one a person feels and hardware wears.
"""

import math

DEAD_BAND = 0.05                # |normalized command| below this is no direction
HUMAN_REVERSALS_PER_S = 2.0     # Loram et al. 2011: ~2 corrections per second


def reversals(commands, dead_band: float = DEAD_BAND) -> int:
    """Return how often the sign of the commands outside the dead band changes."""
    count, last = 0, 0.0
    for command in commands:
        value = float(command)
        if not math.isfinite(value) or abs(value) < dead_band:
            continue
        if last and (value > 0) != (last > 0):
            count += 1
        last = value
    return count


def reversals_per_second(commands, seconds: float, dead_band: float = DEAD_BAND) -> float:
    """Return the reversals of ``commands`` per second of an episode of ``seconds`` (0 if 0 s)."""
    return reversals(commands, dead_band) / seconds if seconds > 0 else 0.0


def chatters(rate: float, limit: float = HUMAN_REVERSALS_PER_S) -> bool:
    """Return whether reversing ``rate`` times per second is faster than a person corrects."""
    return math.isfinite(rate) and rate > limit
