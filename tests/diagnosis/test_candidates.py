"""The candidate library (hems_ros.diagnosis.candidates): real parameter keys, sound bounds,
candidates that do nothing at their neutral values, and the applicability rules."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hems_ros.diagnosis import candidates as lib
from hems_ros.diagnosis.fit import Space
from hems_ros.physics.batch import simulate
from hems_ros.physics.params import ParamError, UnitParams, load_params

SETS = ("table41", "ch5_straight_40n", "ch6_hems_index", "sheathed_calibrated")
TABLE41 = load_params("table41")
ELECTRIC = frozenset({"duty"})
BOTH = frozenset({"position", "wire_force"})


def test_library_names_and_kinds() -> None:
    assert len(lib.RECALIBRATIONS) == 6 and len(lib.EFFECTS) == 10
    assert all(c.kind == "recalibration" for c in lib.RECALIBRATIONS)
    assert all(c.kind == "effect" for c in lib.EFFECTS)
    assert lib.TIMING.kind == "timing" and lib.ALL[-1] is lib.TIMING
    assert len(lib.BY_NAME) == len(lib.ALL) == 17
    assert all(set(c.phases) <= set(lib.PHASES) and c.phases for c in lib.ALL)


@pytest.mark.parametrize("candidate", lib.ALL, ids=lambda c: c.name)
def test_keys_are_real_numeric_parameters(candidate: lib.Candidate) -> None:
    p = UnitParams()
    for par in candidate.parameters:
        for key in (par.key, *par.follow):
            value = p.get(key)
            assert isinstance(value, float) and not isinstance(value, bool), key
            p.replace({key: value})  # a key replace() accepts too
        assert par.scale > 0 and par.lower < par.upper
        if par.log:
            assert par.lower > 0
    for key, value in candidate.switches.items():
        assert type(p.get(key)) is type(value), key
    with pytest.raises(ParamError):
        p.get("load.no_such_key")


@pytest.mark.parametrize("name", SETS)
def test_bounds_are_ordered_for_every_starting_model(name: str) -> None:
    base = load_params(name)
    for c in lib.ALL:
        for par, (lo, hi) in zip(c.parameters, c.bounds(base)):
            assert math.isfinite(lo) and math.isfinite(hi) and lo < hi, (name, par.key, lo, hi)


@pytest.mark.parametrize("candidate", lib.RECALIBRATIONS, ids=lambda c: c.name)
def test_recalibration_bounds_contain_table_4_1(candidate: lib.Candidate) -> None:
    table41 = {
        "kinetics.as0_c": 88.0,
        "kinetics.ms0_c": 72.0,
        "kinetics.ca_pa_per_c": 6.89e6,
        "kinetics.cm_pa_per_c": 6.89e6,
        "constitutive.max_recoverable_strain": 0.038,
        "thermal.h0_w_m2_c": 37.67,
        "thermal.h2_w_m2_c3": 0.01,
        "ambient_temperature_c": 22.0,
    }
    for par, (lo, hi) in zip(candidate.parameters, candidate.bounds(TABLE41)):
        assert TABLE41.get(par.key) == table41[par.key]
        assert lo < table41[par.key] < hi


def test_bounds_that_depend_on_the_starting_model() -> None:
    damping = lib.BY_NAME["load_damping"]
    assert damping.bounds(TABLE41) == [(65.0, 3000.0)]  # missing damping adds to the model's
    preload = lib.BY_NAME["preload_error"]
    assert preload.bounds(TABLE41) == [(2.0, 22.0)]
    assert preload.bounds(TABLE41.replace({"load.pretension_n": 4.0})) == [(0.0, 14.0)]
    warm = lib.BY_NAME["warm_start"]
    for base in (TABLE41, TABLE41.replace({"kinetics.as0_c": 70.0, "ambient_temperature_c": 30.0})):
        ((lo, hi),) = warm.bounds(base)
        # a wire warmed to the upper bound must still start as martensite, 5 degC below As0
        assert lo == 0.0 and base.ambient_temperature_c + hi == pytest.approx(
            base.kinetics.as0_c - 5.0
        )
    ((lo, hi),) = warm.bounds(TABLE41.replace({"kinetics.as0_c": 150.0, "kinetics.af0_c": 160.0}))
    assert hi == 80.0


def _trajectory(p: UnitParams) -> dict[str, np.ndarray]:
    duty = np.zeros(6000)
    duty[200:1700] = 100.0
    duty[3000:3400] = 60.0
    res = simulate(
        p,
        1e-3,
        duty=duty,
        record_every=10,
        channels=["slider_position_m", "wire_force_n", "wire_temperature_c"],
    )
    out = {c: res[c][0] for c in ("slider_position_m", "wire_force_n", "wire_temperature_c")}
    out["encoder"] = res.encoder_position_m[0]
    out["force_reading"] = res.force_reading_n[0]
    return out


def _same(a: UnitParams, b: UnitParams) -> bool:
    ta, tb = _trajectory(a), _trajectory(b)
    return all(np.array_equal(ta[k], tb[k]) for k in ta)


@pytest.mark.parametrize("name", ["table41", "ch6_hems_index"])
def test_off_values_leave_the_physics_unchanged(name: str) -> None:
    base = load_params(name)
    assert _trajectory(base)["slider_position_m"].max() > 5e-3  # the pulse moves the wire
    pool = lib.applicable(base, ELECTRIC, BOTH)
    assert len(pool) == (17 if name == "table41" else 13)
    for c in pool:
        if c.name == "sheath_heat_sink":
            continue  # no sheath value leaves a bare wire bare (below)
        model = c.apply(base, c.off_values(base))
        assert _same(model, base), c.name


def test_switched_effects_change_the_physics_away_from_their_off_values() -> None:
    # the control experiment of the test above: it can tell a change
    changed = (
        ("capstan_friction", [math.pi]),
        ("tendon_friction", [2.0]),
        ("load_damping", [800.0]),
        ("encoder_gain", [1.1]),
        ("force_sensor_drift", [0.5, 0.0]),
    )
    for name, values in changed:
        c = lib.BY_NAME[name]
        assert not _same(c.apply(TABLE41, values), TABLE41), name
    sheath = lib.BY_NAME["sheath_heat_sink"]
    assert not _same(sheath.apply(TABLE41, sheath.off_values(TABLE41)), TABLE41)


def test_space_off_is_where_the_candidate_does_nothing() -> None:
    for name in (
        "capstan_friction",
        "tendon_friction",
        "spring_stiffening",
        "load_damping",
        "supply_sag",
    ):
        space = Space(TABLE41, (lib.BY_NAME[name],))
        assert space.off().tolist() == [0.0], name
    space = Space(TABLE41, (lib.BY_NAME["encoder_gain"],))
    assert space.off()[0] == pytest.approx((1.0 - 0.8) / (1.25 - 0.8))


def test_follow_keys_move_with_their_parameter() -> None:
    heat = lib.BY_NAME["heating_temperatures"]
    moved = heat.apply(TABLE41, [95.5])
    assert (moved.kinetics.as0_c, moved.kinetics.af0_c) == (95.5, 105.5)
    cool = lib.BY_NAME["cooling_temperatures"]
    moved = cool.apply(TABLE41, [60.0])
    assert (moved.kinetics.ms0_c, moved.kinetics.mf0_c) == (60.0, 50.0)
    # the band keeps its width on any base
    base = TABLE41.replace({"kinetics.as0_c": 80.0, "kinetics.af0_c": 93.0})
    assert heat.apply(base, [70.0]).kinetics.af0_c == 83.0
    # the other temperatures stay
    assert (moved.kinetics.as0_c, moved.kinetics.af0_c) == (88.0, 98.0)


def test_apply_turns_on_the_switches_and_sets_the_values() -> None:
    m = lib.BY_NAME["sheath_heat_sink"].apply(TABLE41, [4.0, 2.0])
    assert m.sheath.enabled
    assert (m.sheath.heat_capacity_j_per_k, m.sheath.gap_resistance_k_per_w) == (4.0, 2.0)
    assert m.sheath.helix_heat_capacity_j_per_k == 0.0  # one node
    m = lib.BY_NAME["force_sensor_drift"].apply(TABLE41, [1.0, 0.02])
    assert (m.force_sensor.offset_n, m.force_sensor.drift_n_per_s) == (1.0, 0.02)
    assert TABLE41.force_sensor.offset_n == 0.0  # the base is untouched


def test_warm_start_upper_bound_keeps_a_martensite_start() -> None:
    warm = lib.BY_NAME["warm_start"]
    for name in SETS:
        base = load_params(name)
        ((_, hi),) = warm.bounds(base)
        assert base.ambient_temperature_c + hi < base.kinetics.as0_c
        # the warmest start the fit may try still simulates
        res = simulate(
            warm.apply(base, [hi]), 1e-3, duty=np.zeros(10), channels=["wire_temperature_c"]
        )
        assert res.wire_temperature_c[0, -1] < base.kinetics.as0_c


def _names(base: UnitParams, drives=ELECTRIC, channels=BOTH, names=None) -> list[str]:
    return [c.name for c in lib.applicable(base, drives, channels, names)]


def test_applicable_on_a_bare_wire_with_both_channels_is_the_whole_library() -> None:
    assert _names(TABLE41) == [c.name for c in lib.ALL]


def test_applicable_filters_by_channel() -> None:
    assert "encoder_gain" not in _names(TABLE41, channels=frozenset({"wire_force"}))
    assert "force_sensor_drift" not in _names(TABLE41, channels=frozenset({"position"}))
    assert len(_names(TABLE41, channels=frozenset({"position"}))) == 16


def test_applicable_filters_by_drive() -> None:
    thermal = _names(TABLE41, drives=frozenset({"temperature"}), channels=frozenset({"strain"}))
    # a bare wire heated from outside: no heat balance (convection, ambient, warm start), sheath,
    # transmission, load or supply to fit
    assert thermal == [
        "heating_temperatures",
        "cooling_temperatures",
        "stress_slopes",
        "transformation_strain",
    ]
    current = _names(TABLE41, drives=frozenset({"current"}))
    assert "supply_sag" not in current and "load_damping" in current and len(current) == 16


def test_applicable_skips_effects_the_starting_model_has() -> None:
    hems = load_params("ch6_hems_index")
    assert hems.sheath.enabled and hems.capstan.enabled and hems.glove_friction.enabled
    names = _names(hems)
    assert not {"sheath_heat_sink", "capstan_friction", "tendon_friction", "convection"} & set(
        names
    )
    assert len(names) == 13
    warm = TABLE41.replace({"start.temperature_offset_c": 5.0})
    assert "warm_start" not in _names(warm)


def test_applicable_with_names_asked_for() -> None:
    # in library order whatever order the names come in
    assert _names(TABLE41, names=["supply_sag", "ambient", "encoder_gain"]) == [
        "ambient",
        "supply_sag",
        "encoder_gain",
    ]
    force_only = frozenset({"wire_force"})
    assert _names(TABLE41, channels=force_only, names=["encoder_gain", "ambient"]) == ["ambient"]
    with pytest.raises(KeyError):
        _names(TABLE41, names=["no_such_effect"])


def test_describe_library_lists_every_candidate_with_its_bounds() -> None:
    text = lib.describe_library()
    assert text.count("\n") + 1 == 3 * len(lib.ALL)
    assert "load_damping (effect): viscous damping of the load beyond the model's" in text
    assert "b 65..3000 N s/m [load.damping_n_s_per_m]" in text
    assert "As0 60..110 degC [kinetics.as0_c]" in text
    assert "dT_start 0..61 degC" in text  # As0 88 - 22 ambient - 5


def test_bounds_given_replace_the_librarys_for_their_keys() -> None:
    pool = lib.applicable(TABLE41, ELECTRIC, BOTH)
    given = {
        "kinetics.as0_c": [70, 100],
        "kinetics.ms0_c": {"around_model": [10, 5]},
        "load.damping_n_s_per_m": [0.0, 500.0],
    }
    bounded = {c.name: c for c in lib.with_bounds(pool, TABLE41, given)}
    assert bounded["heating_temperatures"].bounds(TABLE41) == [(70.0, 100.0)]
    ms0 = TABLE41.kinetics.ms0_c
    assert bounded["cooling_temperatures"].bounds(TABLE41) == [(ms0 - 10, ms0 + 5)]
    assert bounded["load_damping"].bounds(TABLE41) == [(0.0, 500.0)]
    # every other parameter keeps the library's range, and the library itself is unchanged
    for c in pool:
        for par, mine, theirs in zip(
            c.parameters, c.bounds(TABLE41), bounded[c.name].bounds(TABLE41)
        ):
            if par.key not in given:
                assert theirs == mine, par.key
    assert lib.BY_NAME["heating_temperatures"].bounds(TABLE41) == [(60.0, 110.0)]


@pytest.mark.parametrize(
    "given, message",
    [
        ({"kinetics.as1_c": [1, 2]}, "kinetics.as1_c: not a parameter of the candidates"),
        ({"kinetics.as0_c": [80]}, "kinetics.as0_c: expected [lower, upper]"),
        ({"kinetics.as0_c": {"around": [5, 5]}}, "expected [lower, upper] or {around_model"),
        ({"kinetics.as0_c": [90, "x"]}, "kinetics.as0_c: expected"),
        ({"kinetics.as0_c": [90, 80]}, "kinetics.as0_c: the range 90..80 is empty"),
        (
            {"kinetics.as0_c": [20, 60]},
            "kinetics.as0_c: the starting model's As0 = 88 degC lies outside 20..60 degC",
        ),
    ],
)
def test_bounds_that_cannot_be_used_are_named(given: dict, message: str) -> None:
    pool = lib.applicable(TABLE41, ELECTRIC, BOTH)
    with pytest.raises(ValueError) as caught:
        lib.with_bounds(pool, TABLE41, given)
    assert message in str(caught.value)
