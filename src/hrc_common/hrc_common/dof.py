"""Degrees of freedom and the wrench axis convention: defined in ``hrc_common.contract``.

Kept as an import path for existing code; new code imports ``hrc_common.contract``.
"""

from hrc_common.contract import (check_dof, DOF_INDEX, DOF_NAME, DOFS,  # noqa: F401
                                 off_axis_components, other_dof, ROTATION, set_wrench_value,
                                 TRANSLATION, wrench_axis, wrench_value)
