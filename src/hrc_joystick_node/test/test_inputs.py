"""Input selection (auto, fallback, hot-plug return) and the /joy adapter, without ROS."""

import pytest

from hrc_joystick_node.inputs import (DEVICE, InputSelector, JOY, JoyInput, SIM, stick_command,
                                      ZERO)


def test_auto_prefers_device_then_joy_then_the_simulated_human():
    selector = InputSelector('auto', 'sim')
    change = selector.update(False, 'cannot open /dev/input/js0', False, '/joy has no publisher')
    assert selector.active == SIM
    assert 'cannot open /dev/input/js0' in change and '/joy has no publisher' in change
    assert 'joy' in selector.update(False, 'absent', True, '/joy alive') and selector.active == JOY
    assert selector.update(True, 'open', True, '/joy alive') is not None
    assert selector.active == DEVICE
    assert selector.update(True, 'open', True, '/joy alive') is None, 'no change, no log'


def test_auto_after_losing_a_real_input_follows_the_fallback_policy():
    selector = InputSelector('auto', 'zero')
    selector.update(False, 'absent', False, 'no publisher')
    assert selector.active == SIM, 'nothing ever connected: the simulated human'
    selector.update(True, 'open', False, 'no publisher')
    assert selector.active == DEVICE
    change = selector.update(False, 'vanished: ENODEV', False, 'no publisher')
    assert selector.active == ZERO and 'lost' in change and 'vanished' in change
    selector.update(True, 'open', False, 'no publisher')
    assert selector.active == DEVICE, 'returns to the device when it reappears'


@pytest.mark.parametrize('fallback', ['sim', 'zero'])
def test_device_mode_falls_back_and_returns(fallback):
    selector = InputSelector('device', fallback)
    selector.update(False, 'cannot open', True, '/joy alive')
    assert selector.active == fallback, '/joy is not used in device mode'
    assert 'no input yet' in selector.reason
    selector.update(True, 'open', False, '')
    assert selector.active == DEVICE
    selector.update(False, 'vanished', False, '')
    assert selector.active == fallback and selector.reason.startswith('lost')


def test_joy_mode_and_sim_mode():
    selector = InputSelector('joy', 'sim')
    selector.update(True, 'open', False, 'silent')
    assert selector.active == SIM, 'the device is not used in joy mode'
    selector.update(True, 'open', True, 'alive')
    assert selector.active == JOY
    selector = InputSelector('sim', 'zero')
    selector.update(True, 'open', True, 'alive')
    assert selector.active == SIM


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
