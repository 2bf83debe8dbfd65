"""Units of the measured quantities and their conversion to the diagnosis's SI units.

A quantity has a default unit (the one :mod:`hems_ros.diagnosis.runs` uses: s, %, A, V,
degC, Pa, N, m, 1) and a few accepted units, each converted as ``value * scale + offset``
(the offset only for K -> degC). Duty stays in % (the HEMS board's unit); a duty given as a
fraction (unit ``1``) is scaled to %. Strings of the condition columns (``protocol``,
``controller``, ``name``) take no unit.
"""

from __future__ import annotations

import numpy as np

from hems_ros.diagnosis.runs import DiagnosisInputError

_TIME = {"s": (1.0, 0.0), "ms": (1e-3, 0.0)}
_LENGTH = {"m": (1.0, 0.0), "mm": (1e-3, 0.0), "um": (1e-6, 0.0), "in": (0.0254, 0.0)}

#: quantity -> unit -> (scale, offset) to the default unit, which comes first.
UNITS: dict[str, dict[str, tuple[float, float]]] = {
    "time": {**_TIME, "min": (60.0, 0.0), "h": (3600.0, 0.0)},
    "duty": {"%": (1.0, 0.0), "1": (100.0, 0.0)},
    "current": {"A": (1.0, 0.0), "mA": (1e-3, 0.0)},
    "voltage": {"V": (1.0, 0.0), "mV": (1e-3, 0.0)},
    "temperature": {"degC": (1.0, 0.0), "K": (1.0, -273.15)},
    "stress": {"Pa": (1.0, 0.0), "kPa": (1e3, 0.0), "MPa": (1e6, 0.0), "GPa": (1e9, 0.0)},
    "load_force": {"N": (1.0, 0.0), "kN": (1e3, 0.0), "mN": (1e-3, 0.0)},
    "wire_force": {"N": (1.0, 0.0), "kN": (1e3, 0.0), "mN": (1e-3, 0.0)},
    "displacement": dict(_LENGTH),
    # a load frame's extensometer (elongation positive), strain over the gauge length
    "extension": dict(_LENGTH),
    "strain": {"1": (1.0, 0.0), "%": (1e-2, 0.0)},
    # the strain a load frame imposes on the wire (an input, elongation positive)
    "prescribed_strain": {"1": (1.0, 0.0), "%": (1e-2, 0.0)},
    # feature tables
    "pulse_length": dict(_TIME),
    "energy": {"J": (1.0, 0.0)},
    "peak_displacement": dict(_LENGTH),
    "peak_force": {"N": (1.0, 0.0)},
    "cooling_time": dict(_TIME),
    "overshoot": dict(_LENGTH),
    "ss_error": dict(_LENGTH),
    "rmse": dict(_LENGTH),
    "rise_time": dict(_TIME),
    "mean_power": {"W": (1.0, 0.0), "mW": (1e-3, 0.0)},
    "cooled_displacement": {"m": (1.0, 0.0), "mm": (1e-3, 0.0)},
}
STRING_QUANTITIES = ("protocol", "controller", "name")
QUANTITY_ALIASES = {"force": "wire_force", "pulse": "pulse_length"}
# other spellings of a unit, per quantity family (the known-units list shows the canonical ones)
_UNIT_ALIASES = {
    "duty": {"percent": "%", "fraction": "1"},
    "temperature": {"C": "degC", "°C": "degC"},
    "strain": {"fraction": "1"},
    "length": {"µm": "um", "μm": "um"},  # micro sign and Greek mu
}
_LENGTHS = (
    "displacement",
    "extension",
    "peak_displacement",
    "overshoot",
    "ss_error",
    "rmse",
    "cooled_displacement",
)


def quantity_names() -> tuple[str, ...]:
    """Every canonical quantity name, numeric first."""
    return tuple(UNITS) + STRING_QUANTITIES


def canonical(quantity: str) -> str:
    """The canonical name of ``quantity`` (aliases resolved); DiagnosisInputError if unknown."""
    name = QUANTITY_ALIASES.get(quantity, quantity)
    if name not in UNITS and name not in STRING_QUANTITIES:
        raise DiagnosisInputError(
            f"unknown quantity {quantity!r} (known: {', '.join(quantity_names())}; "
            f"aliases: {', '.join(f'{a}={q}' for a, q in QUANTITY_ALIASES.items())})"
        )
    return name


def default_unit(quantity: str) -> str | None:
    """The SI/default unit of ``quantity`` (None for a string quantity)."""
    name = canonical(quantity)
    return None if name in STRING_QUANTITIES else next(iter(UNITS[name]))


def check_unit(quantity: str, unit: str | None) -> str | None:
    """The canonical spelling of ``unit`` for ``quantity``; None/empty means the default unit."""
    name = canonical(quantity)
    if name in STRING_QUANTITIES:
        if unit:
            raise DiagnosisInputError(f"{name} is a text column and takes no unit (got {unit!r})")
        return None
    if not unit:
        return default_unit(name)
    family = "length" if name in _LENGTHS else "strain" if name == "prescribed_strain" else name
    spelled = _UNIT_ALIASES.get(family, {}).get(unit, unit)
    if spelled not in UNITS[name]:
        raise DiagnosisInputError(
            f"unknown unit {unit!r} for {name} (known: {', '.join(UNITS[name])})"
        )
    return spelled


def to_si(quantity: str, unit: str | None, values):
    """``values`` (a number or an array) in ``unit`` converted to the default unit of
    ``quantity``."""
    spelled = check_unit(quantity, unit)
    if spelled is None:
        raise DiagnosisInputError(
            f"{canonical(quantity)} is a text column: it has no numeric values"
        )
    scale, offset = UNITS[canonical(quantity)][spelled]
    converted = np.asarray(values, dtype=float) * scale + offset
    return float(converted) if converted.ndim == 0 else converted
