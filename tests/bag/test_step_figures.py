"""`hems step`'s figures, read back from the committed chapter 5 step bag (bags/README.md)."""

from __future__ import annotations

import pytest
from graph_bags import REFERENCES

from hems_ros.client.step_figures import step_figures


def test_step_figures_of_the_reference_bag():
    ref = REFERENCES["ch5_step_index"]
    figures = step_figures(ref.path, ref.finger, ref.pulley_ratio)
    # the figures `hems step` printed when it recorded the bag (bags/README.md)
    assert figures["rmse_mm"] == pytest.approx(10.428, abs=5e-4)
    assert figures["overshoot_mm"] == pytest.approx(0.722, abs=5e-4)
    assert figures["steady_state_error_mm"] == pytest.approx(0.031, abs=5e-4)


@pytest.mark.parametrize(
    "values, span",
    [
        ([0.0, 0.0, 0.02, 0.0], (2, 3)),
        ([0.0, 0.02, 0.02, 0.0], (1, 3)),  # the step's setpoint sent again
        ([0.0, 0.01, 0.0, 0.0, 0.02, 0.0, 0.0], (4, 5)),  # the last step counts
    ],
)
def test_step_span_finds_the_step_among_the_setpoints(values, span):
    from hems_ros.client.step_figures import step_span

    assert step_span(values) == span


@pytest.mark.parametrize("values", [[0.0], [0.0, 0.0, 0.02], []])
def test_step_span_names_a_recording_without_the_step(values):
    from hems_ros.client.step_figures import step_span

    with pytest.raises(
        ValueError, match=f"{len(values)} setpoint messages .* hold no step up and back to 0"
    ):
        step_span(values)
