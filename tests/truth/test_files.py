"""A truth run written as a lab's log and conditions note reads back through the diagnosis's
own loaders: the same samples, the rig's load on the starting model."""

from __future__ import annotations

import numpy as np
import pytest

from hems_ros.diagnosis.csvload import load_table
from hems_ros.diagnosis.inputs import model
from hems_ros.truth.files import COLUMNS, write_run
from hems_ros.truth.measurement import Sensor
from hems_ros.truth.rig import WireRig, simulate

RIG = WireRig()


def test_a_written_run_loads_with_its_columns_and_conditions(tmp_path):
    run = simulate(RIG, [(1.0, 2.8, 4.0), (12.0, 13.5, 4.0)], 24.0)
    sensors = {"contraction": Sensor(noise_sd=0.005, rho=0.5, quantum=0.001)}
    log, note = write_run(run, RIG, tmp_path, "brinson", sensors, np.random.default_rng(3))
    loaded = load_table(log, COLUMNS)
    assert loaded.drive == "current"
    assert loaded.time.size == run.time_s.size
    assert loaded.drive_values.max() == pytest.approx(4.0)
    # outputs are changes from the lead-in at rest, in SI units
    displacement = loaded.outputs["position"]
    assert np.max(np.abs(displacement - run.contraction_m)) < 6 * 0.005e-3 + 0.001e-3
    force = loaded.outputs["wire_force"] - loaded.outputs["wire_force"][0]
    assert np.max(np.abs(force - (run.wire_force_n - run.wire_force_n[0]))) < 1e-6
    params = model("table41", conditions=note)
    assert params.load.pretension_n == RIG.preload_n
    assert params.load.mass_kg == RIG.mass_kg
    assert params.ambient_temperature_c == RIG.ambient_c


def test_a_sensor_for_a_channel_the_log_does_not_have_is_refused(tmp_path):
    run = simulate(RIG, [], 1.0)
    with pytest.raises(ValueError, match="no channel temperature"):
        write_run(run, RIG, tmp_path, "x", {"temperature": Sensor()}, np.random.default_rng())
