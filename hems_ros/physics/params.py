"""Typed parameter set of one SMA actuation unit (dissertation Table 4.1 defaults).

One :class:`UnitParams` is made of nested, frozen groups. SI units everywhere; temperatures
stay in degC because the dissertation's equations (h(T), transformation temperatures,
resistivity) are written in degC, and every such field says so in its name (``*_c``).

Every effect beyond the dissertation's wire model (sheath heat exchange, capstan friction,
glove friction) is its own group with an ``enabled`` flag, so the dissertation's model is
``UnitParams()`` and each extension can be switched on or off for comparison. The
diagnosis extensions (supply sag, stiffening spring, warm start, sensor errors) are off at
their zero (or unit) defaults instead, which leave every result unchanged bit for bit.

Named sets live in ``config/physics/<name>.yaml`` (``load_params("table41")``); a YAML
file mirrors :meth:`UnitParams.to_dict`, missing keys take the defaults, unknown keys are
an error. Every construction is validated: :class:`ParamError` (a ``ValueError``) names the
field and the violated rule. Nothing is clamped or silently corrected.

For fitting, :meth:`UnitParams.replace` takes dotted overrides::

    p = load_params("table41").replace({"kinetics.ca_pa_per_c": 1.2e7, "sheath.enabled": True})
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import yaml

from hems_ros.paths import config_path
from hems_ros.physics.yamlload import load_yaml

LOAD_KINDS = ("hanging_mass", "bias_spring", "hems_finger")


class ParamError(ValueError):
    """A parameter value or file breaks a rule; the message names the field and the rule."""


def _positive(name: str, value: float) -> None:
    if not value > 0:
        raise ParamError(f"{name} = {value!r}: must be > 0")


def _non_negative(name: str, value: float) -> None:
    if not value >= 0:
        raise ParamError(f"{name} = {value!r}: must be >= 0")


class _Group:
    """Shared checks of a parameter group: finite floats, bools where declared."""

    def __post_init__(self) -> None:
        for name, ftype in _field_types(type(self)).items():
            value = getattr(self, name)
            if ftype in ("bool", bool):
                if not isinstance(value, bool):
                    raise ParamError(f"{self._prefix()}{name} = {value!r}: must be true or false")
            elif ftype in ("float", float, "int", int):
                if isinstance(value, bool) or not isinstance(value, (int, float)):
                    raise ParamError(f"{self._prefix()}{name} = {value!r}: must be a number")
                if not math.isfinite(value):
                    raise ParamError(f"{self._prefix()}{name} = {value!r}: must be finite")
        self._check()

    def _check(self) -> None:
        """Raise ParamError naming the field that breaks the group's own rules (none here)."""

    def _prefix(self) -> str:
        return f"{getattr(self, '_GROUP', '')}."

    def _pos(self, *names: str) -> None:
        for n in names:
            _positive(self._prefix() + n, getattr(self, n))

    def _nonneg(self, *names: str) -> None:
        for n in names:
            _non_negative(self._prefix() + n, getattr(self, n))


@dataclass(frozen=True)
class WireGeometry(_Group):
    """Wire geometry (Table 4.1: d, l). S, A and V of Table 4.1 are derived from these."""

    _GROUP = "wire"
    diameter_m: float = 0.508e-3
    length_m: float = 0.9

    def _check(self) -> None:
        self._pos("diameter_m", "length_m")

    @property
    def cross_section_m2(self) -> float:
        """S = pi d^2 / 4 (Table 4.1: 2.027e-7 m2)."""
        return math.pi * self.diameter_m**2 / 4.0

    @property
    def surface_area_m2(self) -> float:
        """A = pi d l (Table 4.1: 1.44e-3 m2)."""
        return math.pi * self.diameter_m * self.length_m

    @property
    def volume_m3(self) -> float:
        """V = S l (Table 4.1: 1.82e-7 m3)."""
        return self.cross_section_m2 * self.length_m


@dataclass(frozen=True)
class Electrical(_Group):
    """Resistivity of each phase, linear in temperature and stress (eq. 4.4)."""

    _GROUP = "electrical"
    rho0_martensite_ohm_m: float = 94.585e-8
    rho0_austenite_ohm_m: float = 90.858e-8
    t0_martensite_c: float = 0.0
    t0_austenite_c: float = 225.0
    drho_dt_martensite_ohm_m_per_c: float = 1.5e-9
    drho_dt_austenite_ohm_m_per_c: float = 0.5e-9
    drho_dsigma_martensite_ohm_m_per_pa: float = 1.5e-17
    drho_dsigma_austenite_ohm_m_per_pa: float = 0.5e-17

    def _check(self) -> None:
        self._pos("rho0_martensite_ohm_m", "rho0_austenite_ohm_m")


@dataclass(frozen=True)
class Thermal(_Group):
    """Wire heat balance (eqs. 4.7-4.12): density, c_p, latent heat, h(T) = h0 + h2 T^2."""

    _GROUP = "thermal"
    density_kg_m3: float = 6450.0
    specific_heat_j_kg_c: float = 837.4
    latent_heat_j_kg: float = 24183.52
    h0_w_m2_c: float = 37.67
    h2_w_m2_c3: float = 0.01

    def _check(self) -> None:
        self._pos("density_kg_m3", "specific_heat_j_kg_c")
        self._nonneg("latent_heat_j_kg", "h0_w_m2_c", "h2_w_m2_c3")


@dataclass(frozen=True)
class Kinetics(_Group):
    """Transformation temperatures at zero stress and their stress slopes (eqs. 4.17-4.25)."""

    _GROUP = "kinetics"
    ms0_c: float = 72.0
    mf0_c: float = 62.0
    as0_c: float = 88.0
    af0_c: float = 98.0
    cm_pa_per_c: float = 6.89e6
    ca_pa_per_c: float = 6.89e6

    def _check(self) -> None:
        if not self.af0_c > self.as0_c:
            raise ParamError(
                f"kinetics.af0_c = {self.af0_c!r}: must be > kinetics.as0_c "
                f"= {self.as0_c!r} (Af <= As)"
            )
        if not self.ms0_c > self.mf0_c:
            raise ParamError(
                f"kinetics.ms0_c = {self.ms0_c!r}: must be > kinetics.mf0_c "
                f"= {self.mf0_c!r} (Ms <= Mf)"
            )
        self._pos("cm_pa_per_c", "ca_pa_per_c")


@dataclass(frozen=True)
class Constitutive(_Group):
    """Brinson rate law with the Reuss mixture (eqs. 4.26-4.31)."""

    _GROUP = "constitutive"
    e_martensite_pa: float = 28e9
    e_austenite_pa: float = 75e9
    alpha_martensite_per_c: float = 6.6e-6
    alpha_austenite_per_c: float = 11e-6
    max_recoverable_strain: float = 0.038
    poisson_ratio: float = 0.33

    def _check(self) -> None:
        self._pos("e_martensite_pa", "e_austenite_pa", "max_recoverable_strain")
        if not 0 <= self.poisson_ratio < 0.5:
            raise ParamError(
                f"constitutive.poisson_ratio = {self.poisson_ratio!r}: must be in [0, 0.5)"
            )


@dataclass(frozen=True)
class Drive(_Group):
    """HEMS PWM stage (dissertation chapter 6): one MOSFET per actuator, 20 V, 4 A limit.

    ``source_resistance_ohm``: supply sag, the resistance in series with the wire while the
    MOSFET conducts (supply output, MOSFET, leads, contacts). A measured current below
    V/R at full duty points at it; it is not wire heat (electrical.pwm_stage). 0: the ideal
    stage. The current and voltage drives do not see it (ideal sources).

    ``input_delay_s``: how much later the wire receives an input than its record says (a
    loop's latency; negative: a record that lags, as a logger holding each sample's past
    period does). Measurement timing, not physics: the diagnosis's replay shifts a recorded
    input by it; the simulated unit applies its commands when they come.
    """

    _GROUP = "drive"
    supply_voltage_v: float = 20.0
    current_limit_a: float = 4.0
    source_resistance_ohm: float = 0.0
    input_delay_s: float = 0.0

    def _check(self) -> None:
        self._pos("supply_voltage_v", "current_limit_a")
        self._nonneg("source_resistance_ohm")


@dataclass(frozen=True)
class Load(_Group):
    """What the slider pulls (eqs. 4.32-4.35 and the HEMS finger).

    One load law in load coordinates x_L = pulley_ratio * x (x: slider displacement,
    contraction positive): F_L = m (x_L'' + g) + b x_L' + pretension + k x_L + k3 x_L^3.
    ``kind`` states which of the dissertation's loads this is and fixes which terms must be
    present: ``hanging_mass`` (eq. 4.33, m > 0; an optional series spring for the chapter 3
    rig), ``bias_spring`` (eq. 4.34, massless, k > 0), ``hems_finger`` (massless bias spring
    with pretension standing in for the glove, on the tendon behind the pulley multiplier).
    Defaults: the dissertation's validation rig, bias spring k = 900 N/m preloaded 12 N.

    ``cubic_stiffness_n_per_m3`` (k3): a spring (or glove and finger) that stiffens as it
    stretches, which a linear k fitted at small strokes underestimates at large ones; 0 is
    the linear law of eqs. 4.33-4.34.
    """

    _GROUP = "load"
    kind: str = "bias_spring"
    mass_kg: float = 0.0
    damping_n_s_per_m: float = 65.0
    stiffness_n_per_m: float = 900.0
    pretension_n: float = 12.0
    pulley_ratio: float = 1.0
    gravity_m_s2: float = 9.81
    cubic_stiffness_n_per_m3: float = 0.0

    def _check(self) -> None:
        if self.kind not in LOAD_KINDS:
            raise ParamError(f"load.kind = {self.kind!r}: must be one of {', '.join(LOAD_KINDS)}")
        self._nonneg(
            "mass_kg",
            "damping_n_s_per_m",
            "stiffness_n_per_m",
            "pretension_n",
            "gravity_m_s2",
            "cubic_stiffness_n_per_m3",
        )
        if not self.pulley_ratio >= 1:
            raise ParamError(f"load.pulley_ratio = {self.pulley_ratio!r}: must be >= 1")
        if self.kind == "hanging_mass":
            self._pos("mass_kg")
        else:
            if self.mass_kg != 0:
                raise ParamError(
                    f"load.mass_kg = {self.mass_kg!r}: must be 0 for load.kind "
                    f"= {self.kind} (massless)"
                )
            self._pos("stiffness_n_per_m")
        if self.kind == "bias_spring" and self.pulley_ratio != 1:
            raise ParamError(
                f"load.pulley_ratio = {self.pulley_ratio!r}: must be 1 for load.kind = bias_spring"
            )

    def static_force_n(self) -> float:
        """Load force at x = 0, at rest, in load coordinates."""
        return self.mass_kg * self.gravity_m_s2 + self.pretension_n


@dataclass(frozen=True)
class Sheath(_Group):
    """Bowden sheath heat exchange (beyond the dissertation's model; dissertation Table 3.1).

    Wire -> sheath conductance G = 1 / (gap_resistance + PTFE conduction); the sheath node
    (``heat_capacity_j_per_k``) loses heat to air through steel conduction + outer convection.
    When enabled the wire no longer convects to air directly (it lies inside the PTFE tube).
    ``gap_resistance_k_per_w`` (imperfect wire-PTFE contact, a thin air film) and
    ``heat_capacity_j_per_k`` are calibrated (config/physics/sheathed_calibrated.yaml).

    With ``helix_heat_capacity_j_per_k`` > 0 the sheath has two nodes: the first (the liner
    and what follows the wire within a pulse) passes heat through
    ``liner_helix_resistance_k_per_w`` to the rest of the steel helix, a slow node that loses
    it to air (sheath.py).
    """

    _GROUP = "sheath"
    enabled: bool = False
    ptfe_inner_diameter_m: float = 0.66e-3
    ptfe_outer_diameter_m: float = 1.168e-3
    ptfe_conductivity_w_per_m_k: float = 0.25
    steel_inner_diameter_m: float = 1.4e-3
    steel_outer_diameter_m: float = 3.0e-3
    steel_conductivity_w_per_m_k: float = 28.5
    outer_convection_w_per_m2_k: float = 13.68
    outer_area_m2: float = 9.77e-3
    gap_resistance_k_per_w: float = 1.80
    heat_capacity_j_per_k: float = 17.0
    helix_heat_capacity_j_per_k: float = 0.0
    liner_helix_resistance_k_per_w: float = 0.0

    def _check(self) -> None:
        self._pos(
            "ptfe_inner_diameter_m",
            "ptfe_outer_diameter_m",
            "ptfe_conductivity_w_per_m_k",
            "steel_inner_diameter_m",
            "steel_outer_diameter_m",
            "steel_conductivity_w_per_m_k",
            "outer_convection_w_per_m2_k",
            "outer_area_m2",
            "heat_capacity_j_per_k",
        )
        self._nonneg(
            "gap_resistance_k_per_w",
            "helix_heat_capacity_j_per_k",
            "liner_helix_resistance_k_per_w",
        )
        if self.helix_heat_capacity_j_per_k > 0 and not self.liner_helix_resistance_k_per_w > 0:
            raise ParamError(
                "sheath.liner_helix_resistance_k_per_w: must be > 0 when "
                "sheath.helix_heat_capacity_j_per_k > 0 (two sheath nodes)"
            )
        if not self.ptfe_outer_diameter_m > self.ptfe_inner_diameter_m:
            raise ParamError("sheath.ptfe_outer_diameter_m: must be > sheath.ptfe_inner_diameter_m")
        if not self.steel_outer_diameter_m > self.steel_inner_diameter_m:
            raise ParamError(
                "sheath.steel_outer_diameter_m: must be > sheath.steel_inner_diameter_m"
            )


@dataclass(frozen=True)
class Capstan(_Group):
    """Capstan friction of the wire in the bent sheath, F_out/F_in = exp(-mu Theta) (eq. 3.1)."""

    _GROUP = "capstan"
    enabled: bool = False
    friction_coefficient: float = 0.04
    bend_angle_rad: float = math.pi

    def _check(self) -> None:
        self._nonneg("friction_coefficient", "bend_angle_rad")


@dataclass(frozen=True)
class GloveFriction(_Group):
    """Coulomb friction between tendon and glove (force-displacement hysteresis, ch. 6)."""

    _GROUP = "glove_friction"
    enabled: bool = False
    force_n: float = 1.0

    def _check(self) -> None:
        self._nonneg("force_n")


@dataclass(frozen=True)
class Encoder(_Group):
    """Incremental quadrature encoder on the slider (RoLin); integer counts.

    ``gain``: scale error of the encoder or of its calibration, counts = round(gain x /
    resolution); 1 is a true scale.
    """

    _GROUP = "encoder"
    resolution_m: float = 1e-6
    gain: float = 1.0

    def _check(self) -> None:
        self._pos("resolution_m", "gain")


@dataclass(frozen=True)
class ForceSensor(_Group):
    """Wire-tension sensor at the fixed end (shoulder module, range up to 50 N).

    ``offset_n`` and ``drift_n_per_s``: a zero error and its drift (load cell creep, an
    amplifier warming up), the sensor reads F + offset + drift t, t the time since the unit
    started; both 0 for an ideal zero.
    """

    _GROUP = "force_sensor"
    range_max_n: float = 50.0
    resolution_n: float = 0.01
    noise_std_n: float = 0.03
    seed: int = 0
    offset_n: float = 0.0
    drift_n_per_s: float = 0.0

    def _check(self) -> None:
        self._pos("range_max_n", "resolution_n")
        self._nonneg("noise_std_n")
        if not isinstance(self.seed, int) or self.seed < 0:
            raise ParamError(f"force_sensor.seed = {self.seed!r}: must be a non-negative integer")


@dataclass(frozen=True)
class Start(_Group):
    """Initial state of a run beyond the cold start (rows.initial_state).

    ``temperature_offset_c``: wire and sheath start this much above the ambient temperature,
    a rig still warm from earlier work; its residual heat shortens the next actuation's
    delay. 0: the cold start.
    """

    _GROUP = "start"
    temperature_offset_c: float = 0.0

    def _check(self) -> None:
        self._nonneg("temperature_offset_c")


_TOP_KEYS = ("name", "description", "ambient_temperature_c")  # the fields outside the groups
_GROUPS: dict[str, type] = {
    "wire": WireGeometry,
    "electrical": Electrical,
    "thermal": Thermal,
    "kinetics": Kinetics,
    "constitutive": Constitutive,
    "drive": Drive,
    "load": Load,
    "sheath": Sheath,
    "capstan": Capstan,
    "glove_friction": GloveFriction,
    "encoder": Encoder,
    "force_sensor": ForceSensor,
    "start": Start,
}


@dataclass(frozen=True)
class UnitParams:
    """All parameters of one actuation unit. ``UnitParams()`` is Table 4.1 (bare wire)."""

    name: str = "table41"
    description: str = ""
    ambient_temperature_c: float = 22.0
    wire: WireGeometry = field(default_factory=WireGeometry)
    electrical: Electrical = field(default_factory=Electrical)
    thermal: Thermal = field(default_factory=Thermal)
    kinetics: Kinetics = field(default_factory=Kinetics)
    constitutive: Constitutive = field(default_factory=Constitutive)
    drive: Drive = field(default_factory=Drive)
    load: Load = field(default_factory=Load)
    sheath: Sheath = field(default_factory=Sheath)
    capstan: Capstan = field(default_factory=Capstan)
    glove_friction: GloveFriction = field(default_factory=GloveFriction)
    encoder: Encoder = field(default_factory=Encoder)
    force_sensor: ForceSensor = field(default_factory=ForceSensor)
    start: Start = field(default_factory=Start)

    def __post_init__(self) -> None:
        """Check the fields outside the groups (each group checks itself)."""
        t = self.ambient_temperature_c
        if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t):
            raise ParamError(f"ambient_temperature_c = {t!r}: must be a finite number")
        if not -50.0 <= t <= 60.0:
            raise ParamError(f"ambient_temperature_c = {t!r}: must be in [-50, 60] degC")
        for gname, cls in _GROUPS.items():
            if not isinstance(getattr(self, gname), cls):
                raise ParamError(f"{gname}: must be a {cls.__name__}")
        if self.sheath.enabled and not self.sheath.ptfe_inner_diameter_m > self.wire.diameter_m:
            raise ParamError(
                "sheath.ptfe_inner_diameter_m: must be > wire.diameter_m (the wire runs inside)"
            )

    @property
    def wire_heat_capacity_j_per_k(self) -> float:
        """Heat capacity rho V c_p of the whole wire (eqs. 4.7-4.12; Table 4.1: 0.985 J/K)."""
        return self.thermal.density_kg_m3 * self.wire.volume_m3 * self.thermal.specific_heat_j_kg_c

    @property
    def wire_latent_heat_j(self) -> float:
        """Latent heat rho V dH of the whole wire's transformation, J.

        Eqs. 4.7-4.12; Table 4.1: 28.45 J.
        """
        return self.thermal.density_kg_m3 * self.wire.volume_m3 * self.thermal.latent_heat_j_kg

    # ----------------------------------------------------------------- conversion
    def to_dict(self) -> dict[str, Any]:
        """Nested plain dict (the YAML layout)."""
        out: dict[str, Any] = {
            "name": self.name,
            "description": self.description,
            "ambient_temperature_c": self.ambient_temperature_c,
        }
        for gname in _GROUPS:
            group = getattr(self, gname)
            out[gname] = {f.name: getattr(group, f.name) for f in fields(group)}
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "parameters") -> "UnitParams":
        """Build from a nested dict; missing keys keep defaults, unknown keys raise."""
        if not isinstance(data, Mapping):
            raise ParamError(f"{source}: top level must be a mapping")
        top = {}
        groups = {}
        for key, value in data.items():
            if key in _GROUPS:
                if not isinstance(value, Mapping):
                    raise ParamError(f"{source}: {key} must be a mapping")
                known = _field_types(_GROUPS[key])
                unknown = sorted(set(value) - set(known))
                if unknown:
                    raise ParamError(
                        f"{source}: unknown key {key}.{unknown[0]} (known: "
                        f"{', '.join(sorted(known))})"
                    )
                groups[key] = _GROUPS[key](
                    **{k: _coerce(_GROUPS[key], k, v) for k, v in value.items()}
                )
            elif key in _TOP_KEYS:
                top[key] = value
            else:
                raise ParamError(f"{source}: unknown key {key}")
        return cls(**top, **groups)

    def replace(self, overrides: Mapping[str, Any] | None = None, /, **kwargs: Any) -> "UnitParams":
        """Copy with overrides: ``{"kinetics.as0_c": 85}`` or ``kinetics__as0_c=85``.

        Only the groups it changes are built and checked again (the others are frozen and
        were checked when made): a fit makes thousands of sets, and rebuilding all fourteen
        groups took 0.2 ms a set.
        """
        changes = dict(overrides or {})
        changes.update({k.replace("__", "."): v for k, v in kwargs.items()})
        top: dict[str, Any] = {}
        groups: dict[str, dict[str, Any]] = {}
        for dotted, value in changes.items():
            parts = dotted.split(".")
            if len(parts) == 1 and parts[0] in _TOP_KEYS:
                top[parts[0]] = value
            elif (
                len(parts) == 2
                and parts[0] in _GROUPS
                and parts[1] in _field_types(_GROUPS[parts[0]])
            ):
                groups.setdefault(parts[0], {})[parts[1]] = _coerce(
                    _GROUPS[parts[0]], parts[1], value
                )
            else:
                raise ParamError(f"replace: unknown parameter {dotted}")
        rebuilt = {
            name: dataclasses.replace(getattr(self, name), **values)
            for name, values in groups.items()
        }
        return dataclasses.replace(self, **top, **rebuilt)

    def get(self, dotted: str) -> Any:
        """Value of a dotted parameter name, e.g. ``get("sheath.heat_capacity_j_per_k")``."""
        obj: Any = self
        for part in dotted.split("."):
            if not hasattr(obj, part) or part.startswith("_"):
                raise ParamError(f"unknown parameter {dotted}")
            obj = getattr(obj, part)
        return obj


_FIELD_TYPES: dict[type, dict[str, Any]] = {}


def _field_types(cls: type) -> dict[str, Any]:
    """Return a group's field names and declared types, in order."""
    known = _FIELD_TYPES.get(cls)
    if known is None:
        known = _FIELD_TYPES[cls] = {f.name: f.type for f in fields(cls)}
    return known


def _coerce(cls: type, key: str, value: Any) -> Any:
    """YAML gives ints for floats written without a dot; keep the declared type."""
    ftype = _field_types(cls)[key]
    if ftype in ("float", float) and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


# --------------------------------------------------------------------- files
def config_dir() -> Path:
    """``config/physics`` of the checkout, else ``share/hems_ros/config/physics`` of the install."""
    return config_path("physics")


def available_configs() -> list[str]:
    """Names of the parameter sets in :func:`config_dir`."""
    return sorted(p.stem for p in config_dir().glob("*.yaml"))


def load_params(path_or_name: str | os.PathLike[str]) -> UnitParams:
    """Read a YAML parameter set: a path, or a name from ``config/physics/<name>.yaml``."""
    path = Path(path_or_name)
    if path.suffix not in (".yaml", ".yml"):
        path = config_dir() / f"{path_or_name}.yaml"
        if not path.is_file():
            raise ParamError(
                f"no parameter set named {path_or_name!r} in {config_dir()} "
                f"(available: {', '.join(available_configs()) or 'none'})"
            )
    try:
        data = load_yaml(path.read_text())
    except yaml.YAMLError as exc:
        raise ParamError(f"{path}: not valid YAML: {exc}") from exc
    return UnitParams.from_dict(data or {}, source=str(path))


def save_params(params: UnitParams, path: str | os.PathLike[str]) -> Path:
    """Write a full parameter set as YAML (round-trips through :func:`load_params`)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump(params.to_dict(), sort_keys=False, default_flow_style=False))
    return path


__all__ = [
    "ParamError",
    "UnitParams",
    "WireGeometry",
    "Electrical",
    "Thermal",
    "Kinetics",
    "Constitutive",
    "Drive",
    "Load",
    "Sheath",
    "Capstan",
    "GloveFriction",
    "Encoder",
    "ForceSensor",
    "Start",
    "LOAD_KINDS",
    "load_params",
    "save_params",
    "config_dir",
    "available_configs",
]
