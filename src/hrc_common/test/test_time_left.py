"""hrc_common.time_left: the time left of a long verb, as a bar on a terminal or plain lines."""

import io

from hrc_common.time_left import duration, TimeLeft


class Clock:
    """A clock the test moves by hand (seconds)."""

    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_duration_reads_as_a_person_says_it():
    assert [duration(s) for s in (0, 44.6, 60, 200, 3599, 7500)] == [
        '0 s', '45 s', '1 min 00 s', '3 min 20 s', '59 min 59 s', '2 h 05 min']


def test_piped_output_is_one_plain_line_per_unit_with_the_time_left():
    clock, stream = Clock(), io.StringIO()
    progress = TimeLeft(4, 'sessions', stream=stream, clock=clock, interactive=False)
    clock.now += 30
    progress.show(1, '[experiment] a done')
    clock.now += 90                                  # 2 done in 120 s: 60 s each, 2 to go
    progress.show(2, '[experiment] b done')
    clock.now += 60
    progress.show(4, '[experiment] c, d done')
    progress.close()
    assert stream.getvalue().splitlines() == [
        '[experiment] a done [1/4 sessions, 30 s, about 1 min 30 s left]',
        '[experiment] b done [2/4 sessions, 2 min 00 s, about 2 min 00 s left]',
        '[experiment] c, d done [4/4 sessions, 3 min 00 s, done]']
    assert '\r' not in stream.getvalue() and '\033' not in stream.getvalue()


def test_a_terminal_gets_a_bar_redrawn_under_the_messages():
    clock, stream = Clock(), io.StringIO()
    progress = TimeLeft(3, 'sessions', stream=stream, clock=clock, interactive=True)
    clock.now += 10
    progress.show(1, 'first')
    clock.now += 10
    progress.show(2, 'second')
    progress.close()
    assert stream.getvalue() == (
        '\r\033[Kfirst\n[########................] 1/3 sessions, 10 s, about 20 s left'
        '\r\033[Ksecond\n[################........] 2/3 sessions, 20 s, about 10 s left\n')
