"""The rule that keeps a lockstep sim within a window of its recorder (pure, no ROS)."""

from hrc_common.qos_table import STREAM_WRITER_DEPTH
from hrc_sim_node.recorder_gate import MAX_WINDOW_STATES, RecorderGate, window_states

PERIOD_NS = 200_000_000


def publish_until_held(gate, first_stamp=0):
    """Publish period states until the gate holds; return the last stamp published."""
    stamp = first_stamp
    gate.on_published(stamp)
    while gate.admits():
        stamp += PERIOD_NS
        gate.on_published(stamp)
    return stamp


def test_the_sim_runs_at_most_the_window_ahead_of_what_the_recorder_took():
    gate = RecorderGate(True, 3, PERIOD_NS)
    last = publish_until_held(gate)
    # nothing acknowledged: the initial state and three more are published, the next step waits
    assert last == 3 * PERIOD_NS
    gate.hold('step 4', now=10.0)
    assert gate.waited(12.5) == 2.5
    assert gate.on_progress(-1) is None                 # an older acknowledgement changes nothing
    assert gate.on_progress(0) == 'step 4'             # the recorder has the first state
    assert gate.held is None and gate.waited(13.0) == 0.0


def test_an_acknowledgement_that_is_still_too_far_behind_keeps_the_step():
    gate = RecorderGate(True, 2, PERIOD_NS)
    gate.on_progress(5 * PERIOD_NS)
    last = publish_until_held(gate, 5 * PERIOD_NS)
    assert last == 8 * PERIOD_NS
    gate.hold('next', now=0.0)
    assert gate.on_progress(5 * PERIOD_NS) is None
    assert gate.on_progress(6 * PERIOD_NS) == 'next'


def test_a_dropped_step_is_not_released_and_a_gate_that_is_off_admits_all():
    gate = RecorderGate(True, 1, PERIOD_NS)
    publish_until_held(gate)
    gate.hold('abandoned', now=0.0)
    gate.drop()                                     # an abort or a reset ends the episode
    assert gate.on_progress(10 * PERIOD_NS) is None
    off = RecorderGate(False, 1, PERIOD_NS)
    for step in range(1000):
        off.on_published(step * PERIOD_NS)
        assert off.admits()


def test_the_window_is_what_the_writers_histories_hold():
    # the human's wrench is the busiest stream: one message per slice of a period
    assert window_states(10) == MAX_WINDOW_STATES
    assert window_states(100) == STREAM_WRITER_DEPTH // 100 - 1
    assert window_states(100) * 100 < STREAM_WRITER_DEPTH
    assert window_states(10 ** 6) == 1
