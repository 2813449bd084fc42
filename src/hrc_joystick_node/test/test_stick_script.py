"""The scripted stick (input ``script``): the file's checks and the human's command from it."""

from hrc_common.contract import SimLimits
from hrc_common.params import ParameterError
from hrc_joystick_node.human_core import HumanCore, HumanParams
from hrc_joystick_node.inputs import SCRIPT
from hrc_joystick_node.human_profile import default_profiles_path, load_profiles
from hrc_joystick_node.stick_script import StickSample, StickScript, StickScriptError
import pytest

SCRIPT_TEXT = 'time,axis,enable\n0,0.0,1\n0.5,0.6,1\n1.2,-0.4,1\n1.5,0.9,0\n'
LIMITS = SimLimits(control_period=0.2, max_force=100.0, max_torque=10.0, human_period=0.02)


def core_with(path, **overrides) -> HumanCore:
    params = HumanParams(input=SCRIPT, script_file=str(path), dof='rotation', **overrides)
    core = HumanCore(params, load_profiles(default_profiles_path()))
    core.set_limits(LIMITS)
    core.on_inputs(False, 'no device', False, 'no /joy')
    return core


def test_a_row_holds_until_the_next_one_and_the_last_to_the_end():
    script = StickScript.parse([line.split(',') for line in SCRIPT_TEXT.splitlines()], 'x')
    assert script.at(0.0) == StickSample(0.0, True)
    assert script.at(0.49) == StickSample(0.0, True)
    assert script.at(0.5) == StickSample(0.6, True)        # a row applies from its own time
    assert script.at(0.1 * 5) == StickSample(0.6, True)    # 0.5 reached by float arithmetic
    assert script.at(1.3) == StickSample(-0.4, True)
    assert script.at(100.0) == StickSample(0.9, False)


def test_a_bad_script_is_refused_with_every_reason(tmp_path):
    path = tmp_path / 'bad.csv'
    path.write_text('time,axis,enable\n0.1,0.0,1\n0.1,1.5,1\nx,0,1\n0.3,0.2,2\n0.4,0.1\n')
    with pytest.raises(StickScriptError) as error:
        StickScript.load(str(path))
    text = str(error.value)
    for reason in ('line 3: time 0.1 s is not after 0.1 s', 'line 3: axis 1.5 is outside',
                   "line 4: not numbers: 'x,0,1'", 'line 5: enable must be 0 or 1',
                   'line 6: 2 values, expected 3', 'the first time must be 0'):
        assert reason in text, text
    (tmp_path / 'header.csv').write_text('t,x\n0,0\n')
    with pytest.raises(StickScriptError, match='the header must be'):
        StickScript.load(str(tmp_path / 'header.csv'))
    with pytest.raises(StickScriptError, match='cannot read it'):
        StickScript.load(str(tmp_path / 'missing.csv'))


def test_the_human_node_refuses_input_script_without_a_usable_file(tmp_path):
    assert HumanParams(input=SCRIPT).check() == [
        'script_file: input script needs a stick script (CSV) path']
    (tmp_path / 'bad.csv').write_text('time,axis\n0,7\n')
    with pytest.raises(ParameterError, match='axis 7 is outside'):
        core_with(tmp_path / 'bad.csv')


def test_the_command_follows_the_script_in_simulation_time_through_the_stick_path(tmp_path):
    """Slices of a period read the script at their own time; deadzone and enable apply."""
    path = tmp_path / 'stick.csv'
    path.write_text(SCRIPT_TEXT)
    core = core_with(path, enable_button=0, deadzone=0.05)
    core.on_session('rotation', True, [])
    # step 2, slice 5: 0.2 * 2 + 0.02 * 5 = 0.5 s -> 0.6 rescaled by the deadzone
    answer = core.answer(0, 2, 0, None, slice_index=5)
    assert answer.source == SCRIPT and answer.source_code == 3   # HumanAction.SOURCE_REPLAY
    assert answer.command == pytest.approx((0.6 - 0.05) / 0.95)
    assert answer.wrench == pytest.approx(answer.command * LIMITS.max_torque)
    assert core.answer(0, 2, 0, None, slice_index=4).command == 0.0   # 0.48 s: still 0
    assert core.answer(0, 6, 0, None, slice_index=0).command == pytest.approx(
        -(0.4 - 0.05) / 0.95)                                          # 1.2 s
    released = core.answer(0, 8, 0, None, slice_index=0)               # 1.6 s: enable 0
    assert released.command == 0.0 and not released.engaged
    assert 'enable button released' in released.detail
    # a new episode starts the script again
    assert core.answer(1, 2, 0, None, slice_index=5).command == answer.command
    # not involved: zero, whatever the script says
    core.on_session('rotation', False, [])
    assert core.answer(1, 3, 0, None).command == 0.0
