"""`hems step`'s figures, read back from the committed chapter 5 step bag (bags/README.md)."""

from __future__ import annotations

import pytest
from graph_bags import REFERENCES

from hems_ros.cli.step import step_figures


def test_step_figures_of_the_reference_bag():
    ref = REFERENCES["ch5_step_index"]
    figures = step_figures(ref.path, ref.finger, ref.pulley_ratio)
    # the figures `hems step` printed when it recorded the bag (bags/README.md)
    assert figures["rmse_mm"] == pytest.approx(10.428, abs=5e-4)
    assert figures["overshoot_mm"] == pytest.approx(0.722, abs=5e-4)
    assert figures["steady_state_error_mm"] == pytest.approx(0.031, abs=5e-4)
