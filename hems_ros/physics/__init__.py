"""SMA actuation-unit physics of the HEMS digital twin (plain numpy/numba, no ROS).

Blocks follow the dissertation (dissertation chapter 4): :mod:`electrical` (4.1-4.5),
:mod:`heat` (4.7-4.12, appendix 4.4), :mod:`kinetics` (4.13-4.25), :mod:`constitutive`
(4.26-4.31), :mod:`loads` (4.32-4.35); beyond it: :mod:`sheath` (Table 3.1),
:mod:`friction` (capstan eq. 3.1, glove Coulomb), :mod:`sensors`. :mod:`kernel` holds the
single-step numba kernel; :mod:`unit` (stepping) and :mod:`batch` (simulate) wrap it.

    from hems_ros.physics import ActuationUnit, simulate, load_params
"""

from hems_ros.physics.batch import SimResult, simulate
from hems_ros.physics.params import ParamError, UnitParams, load_params, save_params
from hems_ros.physics.unit import ActuationUnit, StepResult

__all__ = [
    "ActuationUnit",
    "StepResult",
    "simulate",
    "SimResult",
    "UnitParams",
    "ParamError",
    "load_params",
    "save_params",
]
