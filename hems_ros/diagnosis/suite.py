"""The hidden-effect suite: synthetic measurements with a known truth, diagnosed blind.

For every case the truth is the starting model (``BASE``) with something changed: one
candidate effect switched on at values away from the defaults, a parameter moved, two
effects at once, an effect in another form than its candidate (structural mismatch), an
effect no candidate has, or nothing at all. The truth is driven by an input profile (a
duty pulse train, or the duty a BPID recorded on a repeated staircase), sampled at 100 Hz,
and read through sensors with noise and quantisation at three levels. The diagnosis then
starts from ``BASE`` and sees only the measured input and outputs.

Everything is seeded: the same seed gives the same measurements and the same verdicts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Mapping

import numpy as np

from hems_ros.diagnosis.runs import TimeSeriesRun
from hems_ros.diagnosis.workflow import Diagnosis, diagnose
from hems_ros.experiments.lockstep import simulate_loop
from hems_ros.physics.batch import simulate
from hems_ros.physics.params import UnitParams, load_params

BASE = "table41"
SAMPLE_S = 0.01
DT = 1e-3
#: Sensor noise (standard deviation) of position (m) and wire force (N) per level; the
#: readings are then quantised to the encoder's 1 um and the force sensor's 0.01 N.
NOISE = {"low": (2e-6, 0.02), "mid": (20e-6, 0.1), "high": (100e-6, 0.4)}
POSITION_STEP = 1e-6
FORCE_STEP = 0.01
PROFILES = ("pulses", "staircase")

Distortion = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Case:
    """A truth: what is changed, what the diagnosis should say, the values to recover."""

    name: str
    category: str  # single, structural, pair, parameter, outside, null
    expected: tuple[str, ...]  # candidates the verdict should name (empty: none)
    truth: Mapping[str, object] = field(default_factory=dict)  # physics overrides of BASE
    recover: Mapping[str, float] = field(default_factory=dict)  # key -> true value (SI)
    distortion: Distortion | None = None  # what the sensors do beyond the model's candidates
    description: str = ""

    @property
    def verdicts(self) -> tuple[str, ...]:
        """Verdicts that count as right."""
        # an effect in another form than its candidate may leave a phase above the noise
        # after the candidate is named: partial says so, naming the same candidate
        return {
            "null": ("none",),
            "parameter": ("recalibrated",),
            "outside": ("unexplained", "partial"),
            "structural": ("named", "partial"),
        }.get(self.category, ("named",))


def _ripple(t, x, f):
    """A magnetic encoder's interpolation error: 0.2 mm over a 2 mm pole pitch."""
    return x + 0.2e-3 * np.sin(2 * np.pi * x / 2e-3), f


def _settling_drift(t, x, f):
    """A load cell settling after power-up: 1.5 N approached with a 20 s time constant."""
    return x, f + 1.5 * (1.0 - np.exp(-t / 20.0))


SINGLE = (
    Case(
        "sheath_heat_sink",
        "single",
        ("sheath_heat_sink",),
        {
            "sheath.enabled": True,
            "sheath.heat_capacity_j_per_k": 4.0,
            "sheath.gap_resistance_k_per_w": 2.0,
        },
        {"sheath.heat_capacity_j_per_k": 4.0, "sheath.gap_resistance_k_per_w": 2.0},
        description="C_s 4 J/K, R_gap 2 K/W",
    ),
    Case(
        "capstan_friction",
        "single",
        ("capstan_friction",),
        {"capstan.enabled": True, "capstan.bend_angle_rad": 2 * math.pi},
        {"capstan.bend_angle_rad": 2 * math.pi},
        description="Theta 360 deg (mu 0.04)",
    ),
    Case(
        "tendon_friction",
        "single",
        ("tendon_friction",),
        {"glove_friction.enabled": True, "glove_friction.force_n": 3.0},
        {"glove_friction.force_n": 3.0},
        description="F_c 3 N",
    ),
    Case(
        "load_damping",
        "single",
        ("load_damping",),
        {"load.damping_n_s_per_m": 400.0},
        {"load.damping_n_s_per_m": 400.0},
        description="b 400 N s/m (model 65)",
    ),
    Case(
        "warm_start",
        "single",
        ("warm_start",),
        {"start.temperature_offset_c": 30.0},
        {"start.temperature_offset_c": 30.0},
        description="start 30 degC above ambient",
    ),
    Case(
        "preload_error",
        "single",
        ("preload_error",),
        {"load.pretension_n": 17.0},
        {"load.pretension_n": 17.0},
        description="pretension 17 N (model 12 N)",
    ),
    Case(
        "spring_stiffening",
        "single",
        ("spring_stiffening",),
        {"load.cubic_stiffness_n_per_m3": 1.5e6},
        {"load.cubic_stiffness_n_per_m3": 1.5e6},
        description="k3 1.5e6 N/m3 (12 N more at 20 mm)",
    ),
    Case(
        "supply_sag",
        "single",
        ("supply_sag",),
        {"drive.source_resistance_ohm": 1.5},
        {"drive.source_resistance_ohm": 1.5},
        description="R_s 1.5 ohm",
    ),
    Case(
        "encoder_gain",
        "single",
        ("encoder_gain",),
        {"encoder.gain": 1.1},
        {"encoder.gain": 1.1},
        description="gain 1.1",
    ),
    Case(
        "force_sensor_drift",
        "single",
        ("force_sensor_drift",),
        {"force_sensor.offset_n": 1.0, "force_sensor.drift_n_per_s": 0.02},
        {"force_sensor.offset_n": 1.0, "force_sensor.drift_n_per_s": 0.02},
        description="1 N + 20 mN/s",
    ),
)
OTHERS = (
    Case(
        "sheath_two_nodes",
        "structural",
        ("sheath_heat_sink",),
        {
            "sheath.enabled": True,
            "sheath.heat_capacity_j_per_k": 0.6,
            "sheath.gap_resistance_k_per_w": 1.3,
            "sheath.helix_heat_capacity_j_per_k": 16.0,
            "sheath.liner_helix_resistance_k_per_w": 2.0,
        },
        description="liner 0.6 J/K behind 1.3 K/W, helix 16 J/K behind 2 K/W (candidate: one node)",
    ),
    Case(
        "current_limit",
        "structural",
        ("supply_sag",),
        {"drive.current_limit_a": 3.4},
        description="drive current limited at 3.4 A instead of 4 A (candidate: a "
        "source resistance)",
    ),
    Case(
        "force_settling",
        "structural",
        ("force_sensor_drift",),
        distortion=_settling_drift,
        description="1.5 N (1 - exp(-t / 20 s)) (candidate: offset + linear drift)",
    ),
    Case(
        "friction_and_sag",
        "pair",
        ("tendon_friction", "supply_sag"),
        {
            "glove_friction.enabled": True,
            "glove_friction.force_n": 3.0,
            "drive.source_resistance_ohm": 1.5,
        },
        {"glove_friction.force_n": 3.0, "drive.source_resistance_ohm": 1.5},
        description="F_c 3 N and R_s 1.5 ohm",
    ),
    Case(
        "warm_and_drift",
        "pair",
        ("warm_start", "force_sensor_drift"),
        {
            "start.temperature_offset_c": 30.0,
            "force_sensor.offset_n": 1.0,
            "force_sensor.drift_n_per_s": 0.02,
        },
        {"start.temperature_offset_c": 30.0, "force_sensor.offset_n": 1.0},
        description="start 30 degC warm, force sensor 1 N + 20 mN/s",
    ),
    Case(
        "as_shifted",
        "parameter",
        ("heating_temperatures",),
        {"kinetics.as0_c": 96.0, "kinetics.af0_c": 106.0},
        {"kinetics.as0_c": 96.0},
        description="As0, Af0 8 degC higher",
    ),
    Case(
        "encoder_ripple",
        "outside",
        (),
        distortion=_ripple,
        description="encoder interpolation error 0.2 mm over 2 mm (no candidate has it)",
    ),
    Case("nothing", "null", (), description="the starting model itself"),
)
CASES = SINGLE + OTHERS


# --------------------------------------------------------------------------- input profiles
PULSES = (
    (1.6, 100),
    (1.2, 70),
    (2.0, 100),
    (1.4, 85),
    (1.8, 60),
    (1.0, 100),
    (2.2, 80),
    (1.5, 100),
)
STAIRS_MM = (5.0, 10.0, 15.0)
#: The held-out recording: the same kind of input at other lengths, duties and levels within
#: the fitted ranges, so a correction that only fits the fitted inputs does not carry over.
HELDOUT_PULSES = (
    (1.3, 90),
    (2.1, 75),
    (1.1, 100),
    (1.7, 65),
    (1.9, 95),
    (1.4, 80),
    (2.2, 70),
    (1.2, 85),
)
HELDOUT_STAIRS_MM = (8.0, 14.0, 4.0)


def pulse_profile(plan=PULSES) -> np.ndarray:
    """Duty per 10 ms sample: pulses of (length s, duty %), one every 8 s."""
    n = int(round(8.0 / SAMPLE_S))
    duty = np.zeros(n * len(plan))
    for i, (length, level) in enumerate(plan):
        duty[i * n + 50 : i * n + 50 + int(round(length / SAMPLE_S))] = level
    return duty


def staircase_profile(base: UnitParams, levels_mm=STAIRS_MM) -> np.ndarray:
    """Duty per 10 ms sample a BPID recorded on ``base``: the levels for 3 s each, back to
    rest for 8 s, three times."""
    one = np.concatenate(
        [np.zeros(100)] + [np.full(300, level * 1e-3) for level in levels_mm] + [np.zeros(800)]
    )
    reference = np.tile(one, 3)
    _, duty, *_ = simulate_loop(reference, "bpid", "position", base)
    return duty


def profile(name: str, base: UnitParams) -> tuple[np.ndarray, np.ndarray]:
    """The fitted recording's duty and the held-out recording's. A separate recording is held
    out rather than cycles of one, as a lab keeps a validation run: an effect that acts at the
    start of a run (a warm start) shows only in its first cycle."""
    if name == "pulses":
        return pulse_profile(), pulse_profile(HELDOUT_PULSES)
    return staircase_profile(base), staircase_profile(base, HELDOUT_STAIRS_MM)


# --------------------------------------------------------------------------- measurements
def measure(
    case: Case,
    duty: np.ndarray,
    noise: str,
    seed: int | list[int],
    base: UnitParams | None = None,
    name: str = "",
) -> TimeSeriesRun:
    """The case's truth driven by ``duty`` (per 10 ms sample), read by noisy sensors."""
    base = base or load_params(BASE)
    truth = base.replace(dict(case.truth)) if case.truth else base
    sub = int(round(SAMPLE_S / DT))
    res = simulate(
        truth,
        DT,
        duty=np.repeat(duty, sub),
        record_every=sub,
        channels=["slider_position_m", "wire_force_n"],
    )
    t = np.arange(duty.size) * SAMPLE_S
    x = np.concatenate([[0.0], res.slider_position_m[0][:-1]]) * truth.encoder.gain
    f0 = truth.load.pulley_ratio * truth.load.static_force_n()
    f = (
        np.concatenate([[f0], res.wire_force_n[0][:-1]])
        + truth.force_sensor.offset_n
        + truth.force_sensor.drift_n_per_s * t
    )
    if case.distortion is not None:
        x, f = case.distortion(t, x, f)
    sx, sf = NOISE[noise]
    rng = np.random.default_rng(seed)
    x = np.rint((x + rng.normal(0.0, sx, x.size)) / POSITION_STEP) * POSITION_STEP
    f = np.clip(
        np.rint((f + rng.normal(0.0, sf, f.size)) / FORCE_STEP) * FORCE_STEP,
        0.0,
        truth.force_sensor.range_max_n,
    )
    return TimeSeriesRun(
        name=name or f"{case.name}-{noise}",
        source="synthetic",
        kind="driven",
        time=t,
        drive="duty",
        drive_values=duty,
        outputs={"position": x, "wire_force": f},
        resolution={"position": POSITION_STEP, "wire_force": FORCE_STEP},
    )


@dataclass
class Outcome:
    """What the diagnosis said about one (case, profile, noise, seed)."""

    case: Case
    profile: str
    noise: str
    seed: int
    verdict: str
    named: tuple[str, ...]
    first: str  # the first term accepted (search.Search.opening; '' if none)
    ranking: tuple[str, ...]  # the first selection's candidates, best first
    errors: dict[str, float]  # relative error of each recovered value
    covered: dict[str, bool]  # whether each recovered value's 95 % interval holds the truth
    gap_before: float
    gap_after: float
    beyond_before: float  # the same beyond the noise floor
    beyond_after: float
    unexplained: tuple[str, ...]

    @property
    def right(self) -> bool:
        """Verdict as expected, naming exactly the expected candidates."""
        if self.verdict not in self.case.verdicts:
            return False
        if self.case.category == "parameter":
            return self.first == self.case.expected[0]
        return set(self.named) == set(self.case.expected)

    @property
    def ranked_first(self) -> bool:
        return bool(self.case.expected) and self.first == self.case.expected[0]


def outcome(case: Case, prof: str, noise: str, seed: int, d: Diagnosis) -> Outcome:
    fit = d.search.final
    values: dict[str, float | None] = {
        c.parameters[k].key: None for c in fit.structure for k in range(len(c.parameters))
    }
    i = 0
    for c in fit.structure:
        for par in c.parameters:
            values[par.key] = float(fit.values[i])
            i += 1
    errors = {
        k: abs(x / v - 1.0) for k, v in case.recover.items() if (x := values.get(k)) is not None
    }
    covered = {
        k: d.intervals.of(k)[0] <= v <= d.intervals.of(k)[1]
        for k, v in case.recover.items()
        if values.get(k) is not None and d.intervals is not None
    }
    chosen, ranked = d.search.opening
    first = chosen.structure[-1].name if chosen is not None else ""
    ranking = tuple(f.structure[-1].name for f in ranked)
    named = (
        tuple(n["effect"] for n in d.named())
        if d.verdict != "recalibrated"
        else tuple(c.name for c in d.search.recalibrations)
    )
    g = d.gap
    return Outcome(
        case,
        prof,
        noise,
        seed,
        d.verdict,
        named,
        first,
        ranking,
        errors,
        covered,
        g.heldout_before,
        g.heldout_after,
        g.beyond_noise(g.heldout_before),
        g.beyond_noise(g.heldout_after),
        tuple(d.unexplained),
    )


def run_case(
    case: Case,
    prof: str,
    noise: str,
    seed: int,
    base: UnitParams | None = None,
    duties: tuple[np.ndarray, np.ndarray] | None = None,
    progress=None,
) -> Outcome:
    """Fit on one recording of the profile, hold out the other (its own noise draw)."""
    base = base or load_params(BASE)
    fitted, heldout = profile(prof, base) if duties is None else duties
    run = measure(case, fitted, noise, seed, base)
    check = measure(case, heldout, noise, [seed, 1], base, name=f"{case.name}-{noise}-heldout")
    return outcome(case, prof, noise, seed, diagnose([run], [check], base, progress=progress))
