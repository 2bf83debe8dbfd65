"""The PWM drive from a sagging supply, and the position loop that computes its duty on the
rig itself: each is what its parameters say, and a run reads back as a duty-driven log."""

from __future__ import annotations

import numpy as np
import pytest

from hems_ros.diagnosis.csvload import load_table
from hems_ros.diagnosis.inputs import model
from hems_ros.truth import cases
from hems_ros.truth.drive import Supply, simulate_closed_loop
from hems_ros.truth.files import DUTY_COLUMNS, write_run
from hems_ros.truth.rig import WireRig

RIG = cases.FAMILIES["dissertation"]
TARGETS = [(0.5, 4.5, 0.008), (4.5, 8.5, 0.016)]


def test_the_on_current_is_the_limit_or_what_the_supply_drives_through_every_resistance():
    supply = Supply(
        voltage_v=20.0, current_limit_a=4.0, source_ohm=0.5, cable_ohm=0.3, switch_ohm=0.2
    )
    assert supply.on_current_a(4.0, 0.0) == 4.0  # 20 V / 5 ohm: exactly at the limit
    assert supply.on_current_a(5.0, 0.0) == pytest.approx(20.0 / 6.0)
    assert supply.on_current_a(5.0, 2.0) == pytest.approx(18.0 / 6.0)
    with pytest.raises(ValueError, match="resistances must be >= 0"):
        Supply(cable_ohm=-0.1)


def _holds(run, targets):
    """(mean contraction m, mean duty %) over the last second of each target."""
    out = []
    for _, end, _ in targets:
        last = (run.time_s >= end - 1.0) & (run.time_s < end)
        out.append((run.contraction_m[last].mean(), run.duty_percent[last].mean()))
    return out


def test_the_loop_holds_its_targets_and_pays_a_sag_with_more_duty():
    stiff = simulate_closed_loop(RIG, Supply(), TARGETS, 10.0)
    sagging = simulate_closed_loop(RIG, Supply(source_ohm=1.0, droop_ohm=0.5), TARGETS, 10.0)
    for run in (stiff, sagging):
        for (_, _, target), (reached, _) in zip(TARGETS, _holds(run, TARGETS)):
            assert reached == pytest.approx(target, abs=1.2e-3)  # overshoot cools off slowly
        assert run.duty_percent[run.time_s >= 8.5].max() == 0.0  # off after its last target
    for (_, duty_stiff), (_, duty_sag) in zip(_holds(stiff, TARGETS), _holds(sagging, TARGETS)):
        assert duty_sag > 1.1 * duty_stiff
    # the mean current is the duty's share of the on-current, which the sag lowers
    on = sagging.current_a / np.where(sagging.duty_percent > 0, sagging.duty_percent / 100, 1)
    assert on[sagging.duty_percent > 0].max() < 20.0 / (4.0 + 1.0)


def test_a_warm_wire_starts_at_its_temperature_and_cools_to_the_room():
    warm = WireRig(start_c=45.0)
    run = simulate_closed_loop(warm, Supply(), [], 60.0)
    assert run.temperature_c[0] == 45.0
    # the bare wire's thermal time constant is about 20 s: a tenth of the excess is left
    assert np.all(np.diff(run.temperature_c) <= 0.0)
    assert run.temperature_c[-1] - warm.ambient_c < 0.1 * (45.0 - warm.ambient_c)


def test_a_closed_loop_run_is_logged_with_its_duty_and_its_nominal_supply(tmp_path):
    supply = Supply(voltage_v=24.0, current_limit_a=3.5, source_ohm=1.0)
    run = simulate_closed_loop(RIG, supply, TARGETS, 10.0)
    log, note = write_run(run, RIG, tmp_path, "loop", {}, np.random.default_rng(), supply)
    loaded = load_table(log, DUTY_COLUMNS)
    assert loaded.drive == "duty"
    assert loaded.drive_values == pytest.approx(np.round(run.duty_percent, 9))
    params = model("table41", conditions=note)
    assert (params.drive.supply_voltage_v, params.drive.current_limit_a) == (24.0, 3.5)
    assert params.drive.source_resistance_ohm == 0.0  # the sag is the diagnosis's to find
    with pytest.raises(ValueError, match="needs its supply"):
        write_run(run, RIG, tmp_path, "loop", {}, np.random.default_rng())
