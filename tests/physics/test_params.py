"""Parameter set: Table 4.1 defaults, YAML round trip, validation errors naming field and rule."""

import math

import pytest

from hems_ros.physics.params import (
    ParamError,
    UnitParams,
    available_configs,
    load_params,
    save_params,
)


def test_defaults_are_table_41():
    p = UnitParams()
    assert p.wire.diameter_m == 0.508e-3 and p.wire.length_m == 0.9
    assert p.wire.cross_section_m2 == pytest.approx(2.027e-7, rel=1e-3)
    assert p.wire.surface_area_m2 == pytest.approx(1.44e-3, rel=5e-3)
    assert p.wire.volume_m3 == pytest.approx(1.82e-7, rel=5e-3)
    assert (p.kinetics.ms0_c, p.kinetics.mf0_c, p.kinetics.as0_c, p.kinetics.af0_c) == (
        72,
        62,
        88,
        98,
    )
    assert p.thermal.latent_heat_j_kg == 24183.52 and p.constitutive.max_recoverable_strain == 0.038
    assert p.drive.supply_voltage_v == 20.0 and p.drive.current_limit_a == 4.0
    assert p.encoder.resolution_m == 1e-6 and p.force_sensor.range_max_n == 50.0
    assert not p.sheath.enabled and not p.capstan.enabled and not p.glove_friction.enabled


def test_named_sets_load_and_round_trip(tmp_path):
    assert {"table41", "sheathed_calibrated", "ch5_straight_40n", "ch6_hems_index"} <= set(
        available_configs()
    )
    assert (
        load_params("table41").to_dict()
        == UnitParams().replace(description=load_params("table41").description).to_dict()
    )
    cal = load_params("sheathed_calibrated")
    assert cal.sheath.enabled and cal.load.kind == "hanging_mass"
    path = save_params(cal, tmp_path / "x.yaml")
    assert load_params(path) == cal
    finger = load_params("ch6_hems_index")
    assert finger.load.pulley_ratio == 2.0 and finger.load.pretension_n == 2.0


def test_replace_dotted_and_double_underscore():
    p = UnitParams().replace({"kinetics.as0_c": 85.0}, sheath__enabled=True)
    assert p.kinetics.as0_c == 85.0 and p.sheath.enabled
    assert p.get("kinetics.as0_c") == 85.0
    with pytest.raises(ParamError, match="unknown parameter kinetics.bogus"):
        UnitParams().replace({"kinetics.bogus": 1})


@pytest.mark.parametrize(
    "override, pattern",
    [
        ({"kinetics.af0_c": 80.0}, r"kinetics.af0_c.*Af <= As"),
        ({"kinetics.mf0_c": 75.0}, r"kinetics.ms0_c.*Ms <= Mf"),
        ({"wire.diameter_m": 0.0}, r"wire.diameter_m = 0.0: must be > 0"),
        ({"wire.length_m": -0.9}, r"wire.length_m = -0.9: must be > 0"),
        (
            {"thermal.specific_heat_j_kg_c": math.nan},
            r"thermal.specific_heat_j_kg_c = nan: must be finite",
        ),
        ({"electrical.rho0_austenite_ohm_m": math.inf}, r"must be finite"),
        ({"load.kind": "hanging_mass", "load.mass_kg": -1.0}, r"load.mass_kg = -1.0: must be >= 0"),
        ({"load.kind": "hanging_mass", "load.mass_kg": 0.0}, r"load.mass_kg = 0.0: must be > 0"),
        ({"load.mass_kg": 1.0}, r"must be 0 for load.kind = bias_spring"),
        ({"load.kind": "winch"}, r"load.kind = 'winch': must be one of"),
        ({"sheath.enabled": "yes"}, r"sheath.enabled = 'yes': must be true or false"),
        ({"force_sensor.seed": -1}, r"force_sensor.seed"),
        ({"ambient_temperature_c": 200.0}, r"ambient_temperature_c = 200.0"),
        (
            {"sheath.helix_heat_capacity_j_per_k": 16.0},
            r"sheath.liner_helix_resistance_k_per_w: must be > 0 when",
        ),
        (
            {"sheath.liner_helix_resistance_k_per_w": -1.0},
            r"sheath.liner_helix_resistance_k_per_w = -1.0: must be >= 0",
        ),
    ],
)
def test_bad_values_raise_naming_field_and_rule(override, pattern):
    with pytest.raises(ParamError, match=pattern):
        UnitParams().replace(override)


def test_param_error_is_value_error():
    assert issubclass(ParamError, ValueError)


def test_yaml_unknown_keys_and_missing_name(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("kinetics:\n  as0_c: 88\n  Af0_c: 98\n")
    with pytest.raises(ParamError, match=r"unknown key kinetics.Af0_c"):
        load_params(bad)
    bad.write_text("sheathing: {}\n")
    with pytest.raises(ParamError, match=r"unknown key sheathing"):
        load_params(bad)
    partial = tmp_path / "partial.yaml"
    partial.write_text("kinetics:\n  as0_c: 86\n")
    assert (
        load_params(partial).kinetics.as0_c == 86.0 and load_params(partial).kinetics.af0_c == 98.0
    )
    with pytest.raises(ParamError, match="no parameter set named 'nope'"):
        load_params("nope")
