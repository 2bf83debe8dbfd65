"""The injected sensor faults: a stuck sensor repeats the reading it stuck at until the fault
is cleared, a jump adds 5 mm in whole counts, a failed sensor reads NaN, a saturated load
cell its range, a noise burst fifty times the noise."""

from __future__ import annotations

import math

from hems_ros.graph.sensor_faults import FaultySensor, noise_scale

UM = 1e-6


def test_a_stuck_encoder_repeats_its_reading_until_cleared():
    sensor = FaultySensor()
    assert sensor.encoder("", 10, 10 * UM, UM) == (10, 10 * UM)
    assert sensor.encoder("stuck_encoder", 12, 12 * UM, UM) == (12, 12 * UM)
    assert sensor.encoder("stuck_encoder", 40, 40 * UM, UM) == (12, 12 * UM)
    assert sensor.encoder("", 41, 41 * UM, UM) == (41, 41 * UM)
    assert sensor.encoder("stuck_encoder", 50, 50 * UM, UM) == (50, 50 * UM)  # sticks anew


def test_an_encoder_jump_adds_five_millimetres_of_counts_and_a_failed_one_reads_nan():
    sensor = FaultySensor()
    assert sensor.encoder("encoder_jump", 10, 10 * UM, UM) == (5010, 5010 * UM)
    counts, position = sensor.encoder("nan_encoder", 10, 10 * UM, UM)
    assert counts == 10 and math.isnan(position)


def test_load_cell_faults():
    sensor = FaultySensor()
    assert sensor.force("stuck_force", 3.0, False, 50.0) == (3.0, False)
    assert sensor.force("stuck_force", 9.0, False, 50.0) == (3.0, False)
    assert sensor.force("force_saturation", 9.0, False, 50.0) == (50.0, True)
    assert math.isnan(sensor.force("nan_force", 9.0, False, 50.0)[0])
    assert sensor.force("force_noise_burst", 9.0, False, 50.0) == (9.0, False)
    assert noise_scale("force_noise_burst") == 50.0 and noise_scale("") == 1.0
