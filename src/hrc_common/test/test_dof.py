"""hrc_common.dof: the wrench axis convention."""

from geometry_msgs.msg import Wrench
import pytest

from hrc_common.dof import (off_axis_components, other_dof, ROTATION, set_wrench_value,
                            TRANSLATION, wrench_axis, wrench_value)


def test_axes_of_the_convention():
    assert wrench_axis(TRANSLATION) == ('force', 'z')
    assert wrench_axis(ROTATION) == ('torque', 'x')
    assert other_dof(TRANSLATION) == ROTATION and other_dof(ROTATION) == TRANSLATION
    with pytest.raises(ValueError, match='unknown degree of freedom'):
        other_dof('twist')


def test_set_read_and_report_off_axis():
    wrench = Wrench()
    set_wrench_value(wrench, ROTATION, 0.3)
    assert wrench.torque.x == 0.3 and wrench_value(wrench, ROTATION) == 0.3
    assert wrench_value(wrench, TRANSLATION) == 0.0
    assert off_axis_components(wrench, ROTATION) == {}
    wrench.force.y = 1.0
    wrench.force.z = 2.0
    assert off_axis_components(wrench, ROTATION) == {'force.y': 1.0, 'force.z': 2.0}
    assert off_axis_components(wrench, TRANSLATION) == {'force.y': 1.0, 'torque.x': 0.3}
