"""HumanParams and params/sim_human.yaml agree with the code; bad values are refused."""

from dataclasses import fields

import pytest

from hrc_common.paths import params_dir
from hrc_common.params import as_dict, default_of, ParameterError, with_overrides
from hrc_joystick_node.human_core import HumanParams
from hrc_joystick_node.human_profile import HumanProfile, load_profiles

PARAMS = params_dir()


def test_the_sims_period_and_limits_are_not_parameters_of_the_human():
    """The sim owns them; the node reads them from the sim (test_human_node), no copy here."""
    names = {field.name for field in fields(HumanParams)}
    assert not {'max_force', 'max_torque', 'control_period'} & names
    assert HumanParams().sim_node == 'sim'


def test_the_default_profile_exists_and_the_dataclass_defaults_are_the_skilled_profile():
    profiles = load_profiles(PARAMS / 'sim_human.yaml')
    assert HumanParams().profile in profiles
    skilled = as_dict(profiles['skilled'])
    defaults = {f.name: default_of(f) for f in fields(HumanProfile)}
    del skilled['description'], defaults['description']
    assert skilled == defaults


@pytest.mark.parametrize('overrides, reason', [
    ({'input': 'keyboard'}, "input: 'keyboard' is not one of"),
    ({'deadzone': 0.95}, 'deadzone: 0.95 is above the maximum'),
    ({'axis': -1}, 'axis: -1 is below the minimum'),
    ({'dof': 'both'}, "dof: 'both' is not one of"),
    ({'on_input_lost': 'panic'}, 'on_input_lost'),
])
def test_bad_values_are_refused_with_a_reason(overrides, reason):
    with pytest.raises(ParameterError, match=reason):
        with_overrides(HumanParams(), **overrides)
