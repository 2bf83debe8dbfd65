"""SMA actuation-unit physics of the HEMS digital twin (plain numpy/numba, no ROS).

Blocks follow the dissertation (dissertation chapter 4): :mod:`electrical` (4.1-4.5),
:mod:`heat` (4.7-4.12, appendix 4.4), :mod:`kinetics` (4.13-4.25), :mod:`constitutive`
(4.26-4.31), :mod:`loads` (4.32-4.35); beyond it: :mod:`sheath` (Table 3.1),
:mod:`friction` (capstan eq. 3.1, glove Coulomb), :mod:`sensors`. :mod:`kernel` holds the
single-step numba kernel on the rows of :mod:`rows`; :mod:`unit` (stepping, with the kernel
compiled ahead of time: :mod:`compiled`) and :mod:`batch` (simulate, on the SIMD blocks of
:mod:`block`) wrap it.

    from hems_ros.physics import ActuationUnit, simulate, load_params

The names below are imported on first use, so that a process that only steps units (a node)
never imports the batch API and numba with it.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from hems_ros.physics.batch import SimResult, simulate
    from hems_ros.physics.params import ParamError, UnitParams, load_params, save_params
    from hems_ros.physics.unit import ActuationUnit, StepResult

_MODULE_OF = {
    "ActuationUnit": "unit",
    "StepResult": "unit",
    "simulate": "batch",
    "SimResult": "batch",
    "UnitParams": "params",
    "ParamError": "params",
    "load_params": "params",
    "save_params": "params",
}
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


def __getattr__(name: str) -> Any:
    if name not in _MODULE_OF:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_MODULE_OF[name]}"), name)
