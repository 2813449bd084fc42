"""The levels of /diagnostics: thresholds of the sim's timing and the recorder's disk (pure)."""

from hrc_common.diagnostics import (DISK_ERROR_BYTES, DISK_WARN_BYTES, disk_level, ERROR, OK,
                                    TimingHealth, timing_level, WARN)

PERIOD = 0.2


def test_timing_levels_follow_the_jitter_and_the_late_commands():
    assert timing_level(0.01, PERIOD, 0, 0, 100)[0] == OK
    assert timing_level(0.03, PERIOD, 0, 0, 100) == (WARN, 'period jitter 30 ms')
    assert timing_level(0.15, PERIOD, 0, 0, 100)[0] == ERROR
    assert timing_level(None, PERIOD, 1, 0, 100) == (
        WARN, '1 commands missing and 0 stale in this episode')
    assert timing_level(None, PERIOD, 3, 2, 100)[0] == ERROR      # 5 % of the steps


def test_the_sims_health_counts_an_episode_and_starts_again_with_the_next():
    health = TimingHealth(PERIOD)
    for step, now in enumerate((0.0, 0.2, 0.45, 0.6)):      # one period 50 ms late
        health.on_state(step, {'robot': step == 2}, now)
    health.on_stale()
    status = health.status(True, 'realtime', 3)
    values = {pair.key: pair.value for pair in status.values}
    assert status.level == bytes([ERROR]) and status.name == 'sim: timing'
    assert values['period_jitter_ms'] == '50.0' and values['missing_commands'] == '1'
    assert values['stale_commands'] == '1'
    health.on_state(0, {}, 10.0)        # the next episode: its counts start again; the jitter
    status = health.status(True, 'realtime', 4)   # is the last states', the late one among them
    assert status.level == bytes([WARN]) and status.message == 'period jitter 50 ms'
    assert {pair.key: pair.value for pair in status.values}['missing_commands'] == '0'
    assert {pair.key: pair.value for pair in health.status(
        False, 'lockstep', 4).values}['period_jitter_ms'] == 'n/a (lockstep)'


def test_disk_levels():
    assert disk_level(2 * DISK_WARN_BYTES, '') == (OK, 'writing')
    assert disk_level(DISK_WARN_BYTES - 1, '')[0] == WARN
    assert disk_level(DISK_ERROR_BYTES - 1, '')[0] == ERROR
    assert disk_level(2 * DISK_WARN_BYTES, 'ENOSPC') == (ERROR, 'recording stopped: ENOSPC')
