"""Measured data as the diagnosis takes it: time series runs and tables of test figures.

Everything is in SI units (temperatures in degC) and in the model's sign conventions, so
the loaders (csvload, bagload) do every conversion once and the rest never sees a unit:

- ``position``: slider (wire) displacement, m, contraction positive, relative to the first
  sample;
- ``strain``: wire strain change from the first sample, elongation positive (a contracting
  wire has negative strain change), the materials convention of published thermal cycles;
- ``wire_force``: wire tension, N; ``load_force``: the force the load receives, N (load side
  of the pulley and the transmission losses);
- ``temperature``: wire temperature, degC (an output of a driven run; the input of a
  thermal cycle).

A :class:`TimeSeriesRun` has one input (``drive``): the PWM ``duty`` in %, a ``current`` in
A or a ``voltage`` in V (electrically driven runs), or the wire ``temperature`` in degC
(quasi-static thermal cycles of a bare wire under a load, constant or read row by row).
Each input sample holds until the next sample (zero-order hold), as the HEMS board holds a
duty between updates. A ``prescribed_strain`` run (a load frame moving the wire's end: work
loops, tensile tests) has a second input, the strain the frame imposes, and the wire force
out.

A :class:`FeatureRun` is a table of tests, one row each, with the test's conditions and its
measured figures (the dissertation's tables).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: Outputs a time series run may carry, with their units (the report's display unit).
OUTPUT_UNITS = {
    "position": ("m", "mm", 1e3),
    "strain": ("1", "%", 1e2),
    "wire_force": ("N", "N", 1.0),
    "load_force": ("N", "N", 1.0),
    "temperature": ("degC", "degC", 1.0),
}
DRIVES = ("duty", "current", "voltage", "temperature")
KINDS = ("driven", "thermal_cycle", "prescribed_strain")

#: Figures a feature table may carry: name -> (SI unit, display unit, display scale).
FIGURE_UNITS = {
    "peak_displacement": ("m", "mm", 1e3),
    "peak_force": ("N", "N", 1.0),
    "cooling_time": ("s", "s", 1.0),
    "overshoot": ("m", "mm", 1e3),
    "rise_time": ("s", "s", 1.0),
    "ss_error": ("m", "mm", 1e3),
    "rmse": ("m", "mm", 1e3),
    "mean_power": ("W", "W", 1.0),
}


#: A run with more than this share of its samples dropped for a measurement that is not a
#: number (a sensor's failure value) is refused: it says more about the sensor than the wire.
MAX_BAD_SHARE = 0.05


class DiagnosisInputError(ValueError):
    """Measured data or an option the diagnosis cannot use; the message is one line that
    names the problem (``hems diagnose`` prints it and exits 2)."""


def non_finite_note(source: str, what: str, finite: np.ndarray) -> list[str]:
    """The note on the samples of ``what`` (a topic's field, a table's column) that are not a
    number (``finite`` False), which the loader drops; DiagnosisInputError if they are more
    than MAX_BAD_SHARE of the run."""
    bad = int(np.count_nonzero(~finite))
    if not bad:
        return []
    if bad > MAX_BAD_SHARE * finite.size:
        raise DiagnosisInputError(
            f"{source}: {bad} of {finite.size} samples of {what} are not a number, more than "
            f"{MAX_BAD_SHARE:.0%}: the run is refused"
        )
    return [f"{bad} samples with {what} not a number (NaN or inf) dropped"]


@dataclass(frozen=True)
class TimeSeriesRun:
    """One measured run: an input and the outputs at the same sample instants."""

    name: str
    source: str  # file path, or "<bag folder>:<finger>"
    kind: str  # one of KINDS
    time: np.ndarray  # s since the first sample (time[0] == 0), increasing
    drive: str  # one of DRIVES
    drive_values: np.ndarray  # at each sample instant, held until the next one
    outputs: dict[str, np.ndarray]  # OUTPUT_UNITS name -> values at the sample instants
    resolution: dict[str, float] = field(default_factory=dict)  # known quantisation step per output
    # thermal cycles: the wire stress at the first sample (the dead weight the replay hangs);
    # prescribed-strain runs: the measured preload at the first sample
    stress_pa: float | None = None
    # thermal cycles on a frame whose load wanders: the stress at each sample (Pa); None when
    # it is constant
    stress_values: np.ndarray | None = None
    # prescribed-strain runs: the strain the frame imposes at each sample (elongation positive,
    # change from the first sample)
    strain_values: np.ndarray | None = None
    # a bag's setpoints, for the phase labels only: (time s, mode, value)
    setpoints: tuple[tuple[float, str, float], ...] = ()
    notes: tuple[str, ...] = ()  # what the loader adjusted or dropped, for the report
    # the input as a step function (times s, values) where it also changes between samples (a
    # bag's late duty commands, the unit's watchdog); None: it changes only at the samples
    drive_steps: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def n_samples(self) -> int:
        return int(self.time.size)

    @property
    def duration_s(self) -> float:
        return float(self.time[-1] - self.time[0]) if self.time.size else 0.0


@dataclass(frozen=True)
class FeatureTest:
    """One row of a feature table: the conditions of the test and its measured figures.

    Conditions (SI): ``pulse_s`` and ``current_a`` (a current pulse from rest, held for
    ``pulse_s``), or ``protocol`` and ``controller`` (a closed-loop run of
    :data:`hems_ros.control.references.PROTOCOLS` with that strategy); ``energy_j`` where the
    table gives it; ``cooled_m`` (the displacement below which the wire counts as cooled).
    Figures: :data:`FIGURE_UNITS` names, SI.
    """

    name: str
    conditions: dict[str, float | str]
    figures: dict[str, float]


@dataclass(frozen=True)
class FeatureRun:
    """A table of tests (kind (c) of the measured data).

    ``rig``: the parameters of the rig the table was measured on (dotted key, value), set on
    every model its rows run on, so that tables from several rigs diagnose one wire
    together; a parameter a rig sets is the rig's in every fit."""

    name: str
    source: str
    tests: tuple[FeatureTest, ...]
    notes: tuple[str, ...] = ()
    rig: tuple[tuple[str, object], ...] = ()


Run = TimeSeriesRun | FeatureRun
