"""Input selection (auto, fallback, hot-plug return) and the /joy adapter, without ROS."""

import pytest

from hrc_joystick_node.human_core import HumanParams
from hrc_joystick_node.inputs import (DEVICE, InputSelector, JOY, JoyInput, LOST, MISSING, OK,
                                      PAUSE, SIM, stick_command, ZERO)


def test_auto_prefers_device_then_joy_and_stands_in_only_when_asked():
    selector = InputSelector('auto', 'sim')
    change = selector.update(False, 'cannot open /dev/input/js0', False, '/joy has no publisher')
    assert selector.active == SIM and selector.state == MISSING
    assert 'cannot open /dev/input/js0' in change and '/joy has no publisher' in change
    assert 'simulated human stands in' in change, 'the stand-in is never silent'
    assert 'joy' in selector.update(False, 'absent', True, '/joy alive') and selector.active == JOY
    assert selector.state == OK
    assert selector.update(True, 'open', True, '/joy alive') is not None
    assert selector.active == DEVICE
    assert selector.update(True, 'open', True, '/joy alive') is None, 'no change, no log'


@pytest.mark.parametrize('mode', ['auto', 'device', 'joy'])
def test_a_missing_joystick_is_never_replaced_by_the_simulated_human_by_default(mode):
    # Was: `auto` ran the simulated human when nothing was connected, and `on_input_lost: sim`
    # was the default, silently mixing simulated input into a subject's data.
    selector = InputSelector(mode, HumanParams().on_input_lost)
    assert HumanParams().on_input_lost == PAUSE
    change = selector.update(False, 'cannot open /dev/input/js0', False, '/joy has no publisher')
    assert selector.active == ZERO and selector.state == MISSING
    assert selector.pause_requested
    assert 'no joystick yet' in change and 'session should pause' in change


def test_auto_after_losing_a_real_input_follows_the_fallback_policy():
    selector = InputSelector('auto', 'zero')
    selector.update(False, 'absent', False, 'no publisher')
    assert selector.active == ZERO and selector.state == MISSING
    assert not selector.pause_requested, 'zero holds zero without asking for a pause'
    selector.update(True, 'open', False, 'no publisher')
    assert selector.active == DEVICE
    change = selector.update(False, 'vanished: ENODEV', False, 'no publisher')
    assert selector.active == ZERO and selector.state == LOST
    assert 'joystick disconnected' in change and 'vanished' in change
    assert selector.lost_count == 1
    selector.update(True, 'open', False, 'no publisher')
    assert selector.active == DEVICE and selector.state == OK, 'returns when it reappears'


@pytest.mark.parametrize('fallback', ['sim', 'zero', 'pause'])
def test_device_mode_falls_back_and_returns(fallback):
    expected = SIM if fallback == 'sim' else ZERO
    selector = InputSelector('device', fallback)
    selector.update(False, 'cannot open', True, '/joy alive')
    assert selector.active == expected, '/joy is not used in device mode'
    assert selector.state == MISSING and 'no joystick yet' in selector.status_line()
    selector.update(True, 'open', False, '')
    assert selector.active == DEVICE
    selector.update(False, 'vanished', False, '')
    assert selector.active == expected and selector.state == LOST
    assert selector.status_line().startswith('joystick disconnected')
    assert selector.pause_requested == (fallback == 'pause')


def test_joy_mode_and_sim_mode():
    selector = InputSelector('joy', 'sim')
    selector.update(True, 'open', False, 'silent')
    assert selector.active == SIM, 'the device is not used in joy mode'
    selector.update(True, 'open', True, 'alive')
    assert selector.active == JOY
    selector = InputSelector('sim', 'pause')
    selector.update(True, 'open', True, 'alive')
    assert selector.active == SIM and selector.state == OK and not selector.pause_requested


def test_bad_modes_are_refused():
    with pytest.raises(ValueError, match='input must be one of'):
        InputSelector('keyboard', 'sim')
    with pytest.raises(ValueError, match='on_input_lost'):
        InputSelector('auto', 'hold')


def test_joy_deadline_and_publisher_grace():
    joy = JoyInput(timeout=1.0)
    assert not joy.alive(0.0) and 'no publisher' in joy.status(0.0)
    joy.on_publisher_count(1, now=10.0)
    assert joy.alive(10.5), 'a publisher was just seen: grace period before its first message'
    assert not joy.alive(11.5), 'a publisher that never publishes falls silent'
    joy.on_message([0.0, 0.5], [0, 1], now=12.0)
    assert joy.alive(12.9) and joy.axis(1) == 0.5 and joy.button(1) is True
    assert not joy.alive(13.1) and 'silent' in joy.status(13.1)
    assert joy.axis(5) is None and joy.button(7) is None
    joy.on_publisher_count(0, now=14.0)
    joy.on_publisher_count(1, now=15.0)
    assert joy.alive(15.2), 'a new publisher gets its grace period again'


def test_stick_command_deadzone_inversion_and_enable_button():
    assert stick_command(0.525, None, False, 0.05, False) == (pytest.approx(0.5), True, '')
    assert stick_command(0.525, None, False, 0.05, True)[0] == pytest.approx(-0.5)
    assert stick_command(0.02, None, False, 0.05, False)[0] == 0.0
    assert stick_command(None, None, False, 0.05, False) == (0.0, True, 'axis not reported yet')
    assert stick_command(0.9, False, True, 0.05, False) == (0.0, False,
                                                             'enable button released')
    assert stick_command(0.9, None, True, 0.05, False)[1] is False, 'unknown button = released'
    assert stick_command(1.0, True, True, 0.05, False)[:2] == (1.0, True)
