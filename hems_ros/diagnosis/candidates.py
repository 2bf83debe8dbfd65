"""What the diagnosis may propose: recalibrations of the printed model and missing effects.

A :class:`Candidate` is a set of bounded physical parameters of :class:`UnitParams` (dotted
keys) that the fit may move, plus the switches that turn an effect on. Three kinds:

- ``timing``: when the recorded input reached the wire (``drive.input_delay_s``), for driven
  time series; a timing offset is named as timing, never as physics.
- ``recalibration``: parameters the dissertation's model already has (chapter 4, Table
  4.1), refitted within ranges published for NiTi actuator wires. A value that ends at a
  bound is a finding ("the data ask for more than a NiTi wire has"), not a value to use.
- ``effect``: a mechanism the starting model leaves out, each with the phases it is
  expected to change. Effects the physics already has (sheath, capstan, glove friction)
  are candidates only when the starting model has them switched off.

Every parameter is in SI units; ``unit`` and ``scale`` give the unit the report shows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Callable, Mapping

from hems_ros.physics.params import UnitParams

HEATING, TRANSFORMATION, HOLD, COOLING, REST = (
    "heating",
    "transformation",
    "hold",
    "cooling",
    "rest",
)
PHASES = (HEATING, TRANSFORMATION, HOLD, COOLING, REST)


@dataclass(frozen=True)
class Parameter:
    """One fitted parameter: a dotted :class:`UnitParams` key and its physical bounds (SI).

    ``follow``: keys that move by the same amount (a transformation band shifted whole).
    ``log``: searched on a log scale (a positive range over decades).
    ``neutral``: the value at which a switched-on effect does nothing (a friction force of 0);
    None: the starting model's value. ``lower_is_limit``: see the field.
    """

    key: str
    symbol: str
    unit: str
    scale: float
    lower: float
    upper: float
    log: bool = False
    follow: tuple[str, ...] = ()
    neutral: float | None = None
    # the lower bound is the quantity's own limit (a coefficient that cannot be negative): a
    # fit that ends there found the value, it did not run into a wall
    lower_is_limit: bool = False

    def display(self, value: float) -> float:
        return value / self.scale

    def describe(self, value: float) -> str:
        return f"{self.symbol} = {self.display(value):.4g} {self.unit}".rstrip()


@dataclass(frozen=True)
class Candidate:
    """A recalibration or a missing effect: parameters, switches and where it shows."""

    name: str
    kind: str  # "timing", "recalibration" or "effect"
    title: str
    parameters: tuple[Parameter, ...]
    phases: tuple[str, ...]
    source: str  # where the bounds come from
    switches: Mapping[str, object] = field(default_factory=dict)
    # (starting model, drive kinds of the data, measured channels) -> applicable?
    applies: Callable[[UnitParams, frozenset, frozenset], bool] = lambda p, d, c: True
    # parameter key -> (lower, upper) SI, replacing the library's bounds (a user's wire)
    bound_overrides: Mapping[str, tuple[float, float]] = field(default_factory=dict)

    def apply(self, base: UnitParams, values) -> UnitParams:
        """``base`` with the switches on and the parameters at ``values`` (SI)."""
        changes: dict[str, object] = dict(self.switches)
        for par, value in zip(self.parameters, values):
            changes[par.key] = float(value)
            for key in par.follow:
                changes[key] = float(base.get(key)) + float(value) - float(base.get(par.key))
        return base.replace(changes)

    def bounds(self, base: UnitParams) -> list[tuple[float, float]]:
        """Bounds of each parameter for this starting model (some depend on it)."""
        return [self.bound_overrides.get(par.key) or _bound(base, par) for par in self.parameters]

    def off_values(self, base: UnitParams) -> list[float]:
        """Where each parameter leaves the candidate without effect: its neutral value, or the
        starting model's."""
        return [
            float(base.get(par.key)) if par.neutral is None else par.neutral
            for par in self.parameters
        ]


def _bound(base: UnitParams, par: Parameter) -> tuple[float, float]:
    lower, upper = par.lower, par.upper
    if par.key == "load.damping_n_s_per_m":
        lower = float(base.load.damping_n_s_per_m)  # missing damping adds to what the model has
    if par.key == "load.pretension_n":
        lower, upper = max(0.0, base.load.pretension_n + lower), base.load.pretension_n + upper
    if par.key == "start.temperature_offset_c":
        # a warm wire still has to start as martensite, below As0 (rows.initial_state)
        upper = min(upper, base.kinetics.as0_c - base.ambient_temperature_c - 5.0)
    return lower, upper


def _off(key: str) -> Callable[[UnitParams, frozenset, frozenset], bool]:
    """Applies when the starting model has the effect switched off."""
    return lambda p, drives, channels: not p.get(key)


def _needs_channel(name: str) -> Callable[[UnitParams, frozenset, frozenset], bool]:
    return lambda p, drives, channels: name in channels


def _electric(p: UnitParams, drives: frozenset, channels: frozenset) -> bool:
    """The data are electrically driven (an imposed temperature leaves no heat balance to fit)."""
    return "temperature" not in drives


def _all(*tests):
    return lambda p, d, c: all(t(p, d, c) for t in tests)


# Published ranges (NiTi actuator wires) behind the recalibration bounds.
_SRC_TEMPERATURES = (
    "Table 4.1 (As0 88, Af0 98, Ms0 72, Mf0 62 degC, a Flexinol HT wire rated for about "
    "90 degC); NiTi actuator wires are made with transformation temperatures from about "
    "60 to 110 degC, so the band may move within 60-110 (heating) and 45-95 degC (cooling)"
)
_SRC_SLOPES = (
    "stress slopes of NiTi are roughly 5-15 MPa/degC: Table 4.1 gives 6.89, Brinson's widely "
    "used set C_M 8 and C_A 13.8 (J. Intell. Mater. Syst. Struct. 4, 1993), and the "
    "Clausius-Clapeyron relation with Table 4.1's latent heat and transformation strain "
    "rho dH / (T eps_L) about 11 MPa/degC at 90 degC"
)
_SRC_STRAIN = (
    "Table 4.1 gives 3.8 %; NiTi recovers up to about 8 % in one cycle, and actuator wires "
    "are run at 3-5 % for a long life; bounds 2-6 %"
)
_SRC_CONVECTION = (
    "free convection of a thin horizontal cylinder (Churchill-Chu, appendix 4.4: "
    "h(22 degC) = 42.51 W/m2K for this wire at 90 degC); over wire temperatures of "
    "40-150 degC and room air the correlation stays within about 30-60 W/m2K, nearly flat, "
    "where Table 4.1's h2 = 0.01 W/m2K3 makes h(90 degC) = 119 W/m2K: h2 from 0 (flat) to "
    "0.012"
)
_SRC_AMBIENT = "a laboratory at 10-40 degC"

RECALIBRATIONS: tuple[Candidate, ...] = (
    Candidate(
        "heating_temperatures",
        "recalibration",
        "austenite transformation temperatures As0, Af0",
        (Parameter("kinetics.as0_c", "As0", "degC", 1.0, 60.0, 110.0, follow=("kinetics.af0_c",)),),
        (HEATING, TRANSFORMATION),
        _SRC_TEMPERATURES,
    ),
    Candidate(
        "cooling_temperatures",
        "recalibration",
        "martensite transformation temperatures Ms0, Mf0",
        (Parameter("kinetics.ms0_c", "Ms0", "degC", 1.0, 45.0, 95.0, follow=("kinetics.mf0_c",)),),
        (COOLING,),
        _SRC_TEMPERATURES,
    ),
    Candidate(
        "stress_slopes",
        "recalibration",
        "stress slopes C_A, C_M of the transformation temperatures",
        (
            Parameter("kinetics.ca_pa_per_c", "C_A", "MPa/degC", 1e6, 5e6, 15e6),
            Parameter("kinetics.cm_pa_per_c", "C_M", "MPa/degC", 1e6, 5e6, 15e6),
        ),
        (TRANSFORMATION, COOLING),
        _SRC_SLOPES,
    ),
    Candidate(
        "transformation_strain",
        "recalibration",
        "maximum recoverable strain eps_L",
        (Parameter("constitutive.max_recoverable_strain", "eps_L", "%", 1e-2, 0.02, 0.06),),
        (TRANSFORMATION, HOLD),
        _SRC_STRAIN,
    ),
    Candidate(
        "convection",
        "recalibration",
        "free-convection law h(T) = h0 + h2 T^2 of the bare wire",
        (
            Parameter("thermal.h0_w_m2_c", "h0", "W/m2K", 1.0, 30.0, 60.0),
            # 0: a coefficient that does not grow with the wire's temperature
            Parameter("thermal.h2_w_m2_c3", "h2", "W/m2K3", 1.0, 0.0, 0.012, lower_is_limit=True),
        ),
        (HEATING, COOLING),
        _SRC_CONVECTION,
        applies=_all(_off("sheath.enabled"), _electric),
    ),
    Candidate(
        "ambient",
        "recalibration",
        "ambient temperature",
        (Parameter("ambient_temperature_c", "T_amb", "degC", 1.0, 10.0, 40.0),),
        (HEATING, COOLING, REST),
        _SRC_AMBIENT,
        applies=_electric,
    ),
)

EFFECTS: tuple[Candidate, ...] = (
    Candidate(
        "sheath_heat_sink",
        "effect",
        "Bowden sheath as a heat sink (heat capacity, wire-sheath contact)",
        (
            Parameter("sheath.heat_capacity_j_per_k", "C_s", "J/K", 1.0, 0.2, 30.0, log=True),
            Parameter("sheath.gap_resistance_k_per_w", "R_gap", "K/W", 1.0, 0.05, 10.0, log=True),
        ),
        (HEATING, TRANSFORMATION, COOLING),
        "chapter 3 sheath facts and Table 3.1 (PTFE + steel helix about 17 J/K; wire-to-air "
        "7.89 K/W sheathed against 14.2 K/W bare)",
        switches={
            "sheath.enabled": True,
            "sheath.helix_heat_capacity_j_per_k": 0.0,
            "sheath.liner_helix_resistance_k_per_w": 0.0,
        },
        applies=_all(_off("sheath.enabled"), _electric),
    ),
    Candidate(
        "capstan_friction",
        "effect",
        "capstan friction of the wire over the sheath's bends",
        (
            Parameter(
                "capstan.bend_angle_rad",
                "Theta",
                "deg",
                math.pi / 180,
                0.0,
                4 * math.pi,
                neutral=0.0,
            ),
        ),
        (TRANSFORMATION, HOLD, COOLING),
        "eq. 3.1, F_out/F_in = exp(-mu Theta) with mu = 0.04 (PTFE): 0.88 predicted, 0.84 measured "
        "over pi; bends up to two full turns",
        switches={"capstan.enabled": True},
        applies=_all(_off("capstan.enabled"), _electric),
    ),
    Candidate(
        "tendon_friction",
        "effect",
        "Coulomb friction of the tendon in the glove",
        (Parameter("glove_friction.force_n", "F_c", "N", 1.0, 0.0, 10.0, neutral=0.0),),
        (TRANSFORMATION, HOLD, COOLING),
        "chapter 6 force-displacement hysteresis (tendon-glove and bench friction); up to 10 N",
        switches={"glove_friction.enabled": True},
        applies=_all(_off("glove_friction.enabled"), _electric),
    ),
    Candidate(
        "load_damping",
        "effect",
        "viscous damping of the load beyond the model's",
        (Parameter("load.damping_n_s_per_m", "b", "N s/m", 1.0, 0.0, 3000.0),),
        (TRANSFORMATION, COOLING),
        "eq. 4.33's b (65 N s/m in Table 4.1) identified on the dissertation's rig; a glove or a "
        "bench adds its own, up to about 3000 N s/m (a 30 mm/s stroke then meets 90 N)",
        applies=_electric,
    ),
    Candidate(
        "warm_start",
        "effect",
        "wire and sheath warmer than the room at the start",
        (Parameter("start.temperature_offset_c", "dT_start", "degC", 1.0, 0.0, 80.0),),
        (HEATING,),
        "a rig still warm from earlier pulses; the wire must start as martensite, below As0",
        applies=_all(lambda p, d, c: p.start.temperature_offset_c == 0, _electric),
    ),
    Candidate(
        "preload_error",
        "effect",
        "bias-spring pretension other than the model's",
        (Parameter("load.pretension_n", "F_0", "N", 1.0, -10.0, 10.0),),
        (REST, HEATING, TRANSFORMATION, HOLD),
        "the pretension is set by hand on the rig; +-10 N of the model's",
        applies=_electric,
    ),
    Candidate(
        "spring_stiffening",
        "effect",
        "bias spring that stiffens with stroke (cubic term)",
        (Parameter("load.cubic_stiffness_n_per_m3", "k3", "N/m3", 1.0, 0.0, 5e6),),
        (TRANSFORMATION, HOLD),
        "the chapter 6 glove and spring are nonlinear; up to 40 N extra at 20 mm of load travel",
        applies=_electric,
    ),
    Candidate(
        "supply_sag",
        "effect",
        "drive supply sagging under load (source resistance)",
        (Parameter("drive.source_resistance_ohm", "R_s", "ohm", 1.0, 0.0, 5.0),),
        (HEATING, TRANSFORMATION, HOLD),
        "the 20 V supply and MOSFET channel; up to 5 ohm (the current then stays below 2.3 A)",
        applies=lambda p, drives, c: drives == frozenset({"duty"}),
    ),
    Candidate(
        "encoder_gain",
        "effect",
        "displacement sensor scale error",
        (Parameter("encoder.gain", "g_x", "", 1.0, 0.8, 1.25),),
        (TRANSFORMATION, HOLD, COOLING),
        "a miscalibrated encoder scale or pulley lever; +-20 %",
        applies=_needs_channel("position"),
    ),
    Candidate(
        "force_sensor_drift",
        "effect",
        "force sensor offset and drift",
        (
            Parameter("force_sensor.offset_n", "F_off", "N", 1.0, -5.0, 5.0),
            Parameter("force_sensor.drift_n_per_s", "dF/dt", "mN/s", 1e-3, -0.05, 0.05),
        ),
        (REST, HEATING, TRANSFORMATION, HOLD, COOLING),
        "strain-gauge load cells drift with temperature and time; +-5 N, +-50 mN/s",
        applies=_needs_channel("wire_force"),
    ),
)

# The input's timing against the outputs: measurement, not physics. Its range follows the
# data's sample period (the workflow sets it, ``diagnose(timing_range_s=...)``); this one is
# what the library shows.
TIMING = Candidate(
    "input_timing",
    "timing",
    "the input reaching the wire earlier or later than its record says",
    (Parameter("drive.input_delay_s", "dt_in", "ms", 1e-3, -0.03, 0.03, neutral=0.0),),
    (HEATING, TRANSFORMATION, COOLING),
    "a logger's sample-and-hold or a loop's latency: three sample periods either way "
    "(--timing-range)",
    applies=_electric,
)

ALL: tuple[Candidate, ...] = RECALIBRATIONS + EFFECTS + (TIMING,)
BY_NAME: dict[str, Candidate] = {c.name: c for c in ALL}

#: Parameters that only change what a sensor reads, not the physics (a replay shares the
#: simulation of sets that differ only in these).
SENSOR_KEYS = ("encoder.gain", "force_sensor.offset_n", "force_sensor.drift_n_per_s")


def applicable(
    base: UnitParams, drives: frozenset, channels: frozenset, names: list[str] | None = None
) -> list[Candidate]:
    """Candidates that make sense for this starting model and data, in library order."""
    unknown = sorted(set(names or ()) - set(BY_NAME))
    if unknown:
        raise KeyError(f"unknown candidate {unknown[0]!r}")
    chosen = ALL if names is None else tuple(c for c in ALL if c.name in names)
    return [c for c in chosen if c.applies(base, drives, channels)]


def parameter_keys() -> dict[str, Parameter]:
    """Every parameter of the library by key."""
    return {par.key: par for c in ALL for par in c.parameters}


def with_bounds(
    pool: list[Candidate], base: UnitParams, given: Mapping[str, object]
) -> list[Candidate]:
    """``pool`` with the bounds ``given`` per parameter key: ``[lower, upper]`` (SI), or
    ``{around_model: [below, above]}``, the starting model's value minus ``below`` to plus
    ``above``. ValueError naming the key for an unknown key, a malformed or empty range, or a
    recalibration whose starting value lies outside its range."""
    keys = parameter_keys()
    bounds: dict[str, tuple[float, float]] = {}
    for key, spec in given.items():
        if key not in keys:
            raise ValueError(f"{key}: not a parameter of the candidates (known: {', '.join(keys)})")
        bounds[key] = _range(key, spec, float(base.get(key)))
    for c in pool:
        for par in c.parameters:
            if c.kind == "recalibration" and par.key in bounds:
                lower, upper = bounds[par.key]
                value = float(base.get(par.key))
                if not lower <= value <= upper:
                    raise ValueError(
                        f"{par.key}: the starting model's {par.describe(value)} lies outside "
                        f"{par.display(lower):.4g}..{par.display(upper):.4g} {par.unit}".rstrip()
                    )
    return [
        replace(c, bound_overrides={p.key: bounds[p.key] for p in c.parameters if p.key in bounds})
        for c in pool
    ]


def _range(key: str, spec: object, value: float) -> tuple[float, float]:
    around = isinstance(spec, Mapping) and set(spec) == {"around_model"}
    pair = spec["around_model"] if around else spec  # type: ignore[index]
    if not (
        isinstance(pair, (list, tuple))
        and len(pair) == 2
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in pair)
        and all(math.isfinite(v) for v in pair)
    ):
        raise ValueError(
            f"{key}: expected [lower, upper] or {{around_model: [below, above]}} in SI units, "
            f"got {spec!r}"
        )
    lower, upper = (value - pair[0], value + pair[1]) if around else (pair[0], pair[1])
    if not lower < upper:
        raise ValueError(f"{key}: the range {lower:g}..{upper:g} is empty")
    return float(lower), float(upper)


def describe_library() -> str:
    """The library as text: each candidate's parameters (with their keys), bounds, phases and
    sources."""
    base = UnitParams()
    lines = []
    for c in ALL:
        bounds = ", ".join(
            f"{p.symbol} {p.display(lo):.4g}..{p.display(hi):.4g} {p.unit}".rstrip() + f" [{p.key}]"
            for p, (lo, hi) in zip(c.parameters, c.bounds(base))
        )
        lines += [
            f"{c.name} ({c.kind}): {c.title}",
            f"    {bounds}; changes {', '.join(c.phases)}",
            f"    bounds: {c.source}",
        ]
    return "\n".join(lines)
