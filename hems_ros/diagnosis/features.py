"""Tables of test figures (the dissertation's tables) prepared for fitting.

Each row is re-run on the model under its conditions: a current pulse from rest (peak
displacement, peak wire force, cooling time back to the ``cooled`` displacement), or a
closed-loop protocol (RMSE, overshoot, steady-state error, rise time, mean power), and
the model's figures are compared with the measured ones. A published figure carries no
noise figure, so each is weighed by an assumed uncertainty: ``RELATIVE`` of its value, at
least ``ABSOLUTE`` (the resolution tables of this kind are printed to and read off with).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hems_ros.control import metrics
from hems_ros.diagnosis import phases
from hems_ros.diagnosis.dataset import Prediction, Split, three_roles
from hems_ros.diagnosis.runs import FIGURE_UNITS, DiagnosisInputError, FeatureRun, FeatureTest
from hems_ros.experiments.lockstep import run_protocol
from hems_ros.physics.batch import simulate
from hems_ros.physics.params import UnitParams

RELATIVE = 0.05
ABSOLUTE = {
    "peak_displacement": 0.2e-3,
    "peak_force": 0.5,
    "cooling_time": 0.2,
    "overshoot": 0.05e-3,
    "rise_time": 0.05,
    "ss_error": 0.01e-3,
    "rmse": 0.02e-3,
    "mean_power": 0.5,
}
PULSE_FIGURES = ("peak_displacement", "peak_force", "cooling_time")
LOOP_FIGURES = {
    "rmse": ("rmse", 1e-3),
    "overshoot": ("overshoot", 1e-3),
    "ss_error": ("ss_error", 1e-3),
    "rise_time": ("rise_time_s", 1.0),
    "mean_power": ("apc_w", 1.0),
}
DEFAULT_CURRENT_A = 4.0
COOLING_WINDOW_S = 15.0
PULSE_DT = 2e-3
MIN_ROWS = 3


def uncertainty(figure: str, value: float) -> float:
    return max(RELATIVE * abs(value), ABSOLUTE[figure])


@dataclass
class FeatureData:
    """Rows of one or more tables, the held-out rows, and each figure's uncertainty."""

    runs: list[FeatureRun]
    tests: list[tuple[FeatureRun, FeatureTest]]
    split: Split
    dt: float = PULSE_DT
    cost_spread: float = 0.0  # a published figure's uncertainty is assumed, not estimated

    @property
    def channels(self) -> list[str]:
        return [f for f in FIGURE_UNITS if any(f in t.figures for _, t in self.tests)]

    @property
    def drives(self) -> frozenset:
        """Current pulses and closed loops on the PWM stage (duty)."""
        return frozenset(
            ("current" if "pulse_s" in t.conditions else "duty") for _, t in self.tests
        )

    @property
    def measured(self) -> frozenset:
        """What the figures are read from: the displacement sensor, the force sensor."""
        return frozenset(
            ("wire_force" if name == "peak_force" else "position")
            for name in self.channels
            if name not in ("cooling_time", "rise_time", "mean_power")
        )

    def predict(self, sets: list[UnitParams]) -> list[Prediction]:
        figures = self._figures(sets)
        out = []
        for i in range(len(sets)):
            outputs = [figures[i][j] for j in range(len(self.tests))]
            out.append(
                Prediction(
                    outputs,
                    self._weighted(outputs, self.split.train[0]),
                    self._weighted(outputs, self.split.heldout[0]),
                )
            )
        return out

    def _weighted(self, outputs: list[dict[str, float]], mask: np.ndarray) -> np.ndarray:
        parts = []
        for (_, test), sim, take in zip(self.tests, outputs, mask):
            if take:
                for name in self.channels:
                    if name in test.figures:
                        value = sim.get(name, math.nan)
                        r = (value - test.figures[name]) / uncertainty(name, test.figures[name])
                        parts.append(r if math.isfinite(r) else 1e3)
        return np.array(parts)

    def _figures(self, sets: list[UnitParams]) -> list[list[dict[str, float]]]:
        """Model figures, [set][test]; each table's rows on the sets with its rig."""
        out: list[list[dict[str, float]]] = [[{} for _ in self.tests] for _ in sets]
        rigs: dict[tuple, list[int]] = {}
        for j, (run, _) in enumerate(self.tests):
            rigs.setdefault(run.rig, []).append(j)
        for rig, rows in rigs.items():
            rigged = [s.replace(dict(rig)) for s in sets] if rig else sets
            self._rig_figures(rigged, rows, out)
        return out

    def _rig_figures(
        self, sets: list[UnitParams], rows: list[int], out: list[list[dict[str, float]]]
    ) -> None:
        pulses = [j for j in rows if "pulse_s" in self.tests[j][1].conditions]
        if pulses:
            for (i, j), fig in zip(
                [(i, j) for i in range(len(sets)) for j in pulses],
                _pulse_figures(sets, [self.tests[j][1] for j in pulses], self.dt),
            ):
                out[i][j] = fig
        loops: dict[tuple[str, str], list[int]] = {}
        for j in rows:
            t = self.tests[j][1]
            if "protocol" in t.conditions:
                loops.setdefault(
                    (str(t.conditions["protocol"]), str(t.conditions.get("controller", "bpid"))), []
                ).append(j)
        for (protocol, strategy), same in loops.items():
            for i, figs in enumerate(_loop_figures(protocol, strategy, sets)):
                for j in same:
                    out[i][j] = {
                        name: figs.get(key, math.nan) * scale
                        for name, (key, scale) in LOOP_FIGURES.items()
                    }

    def headline(self, start: Prediction) -> str:
        """The figure the starting model misses most on held-out rows, in uncertainty units."""
        mask = self.split.heldout[0] if self.split.heldout[0].any() else self.split.train[0]

        def cost(name: str) -> float:
            r = [
                (start.outputs[j].get(name, math.nan) - t.figures[name])
                / uncertainty(name, t.figures[name])
                for j, ((_, t), take) in enumerate(zip(self.tests, mask))
                if take and name in t.figures
            ]
            r = [x if math.isfinite(x) else 1e3 for x in r]
            return float(np.mean(np.square(r))) if r else 0.0

        return max(self.channels, key=cost)

    def rmse(self, prediction: Prediction, name: str, which: str) -> float:
        mask = self.split.role(which)[0]
        errs = [
            prediction.outputs[j].get(name, math.nan) - t.figures[name]
            for j, ((_, t), take) in enumerate(zip(self.tests, mask))
            if take and name in t.figures
        ]
        return metrics.rms(errs)


def _loop_figures(protocol: str, strategy: str, sets: list[UnitParams]) -> list[dict[str, float]]:
    """The closed-loop figures (lockstep.run_protocol) of every set; a run that a controller
    fault or a non-finite plant cut short has none. Sets with the same physics and sensors
    run once."""
    done: dict[UnitParams, dict[str, float]] = {}
    out = []
    for p in sets:
        if p not in done:
            run = run_protocol(protocol, strategy, p)
            done[p] = {} if run.fault else run.metrics
        out.append(done[p])
    return out


def _pulse_figures(
    sets: list[UnitParams], tests: list[FeatureTest], dt: float
) -> list[dict[str, float]]:
    """Peak displacement, peak force and cooling time of every (set, test) pair, set-major."""
    longest = max(float(t.conditions["pulse_s"]) for t in tests)
    n = int(round((longest + COOLING_WINDOW_S) / dt))
    drives = np.zeros((len(tests), n))
    for j, t in enumerate(tests):
        drives[j, : int(round(float(t.conditions["pulse_s"]) / dt))] = float(
            t.conditions.get("current_a", DEFAULT_CURRENT_A)
        )
    rows = [s for s in sets for _ in tests]
    res = simulate(
        rows,
        dt,
        current=np.tile(drives, (len(sets), 1)),
        channels=["slider_position_m", "wire_force_n"],
    )
    out = []
    for i, p in enumerate(rows):
        test = tests[i % len(tests)]
        x = res.slider_position_m[i] * p.encoder.gain
        force = (
            res.wire_force_n[i] + p.force_sensor.offset_n + p.force_sensor.drift_n_per_s * res.time
        )
        end = int(round(float(test.conditions["pulse_s"]) / dt)) - 1
        cooled = float(test.conditions.get("cooled_m", 0.005 * p.wire.length_m))
        out.append(
            {
                "peak_displacement": float(x.max()),
                "peak_force": float(force.max()),
                "cooling_time": _cooling_time(x, end, dt, cooled),
            }
        )
    return out


def _cooling_time(x: np.ndarray, end: int, dt: float, cooled: float) -> float:
    """Seconds after the pulse until back at ``cooled`` (0 if it never passed it; the rest
    of the window if it never came back)."""
    if x.max() <= cooled:
        return 0.0
    back = np.flatnonzero(x[end:] <= cooled)
    return float(back[0] * dt) if back.size else float((x.size - end) * dt)


def prepare(runs: list[FeatureRun], heldout: list[FeatureRun], dt: float = PULSE_DT) -> FeatureData:
    """All rows; held out: the ``heldout`` tables, or every third row from the second."""
    tests = [(run, t) for run in list(runs) + list(heldout) for t in run.tests]
    for run, t in tests:
        if "pulse_s" not in t.conditions and "protocol" not in t.conditions:
            raise DiagnosisInputError(
                f"{run.name}, {t.name}: a test needs its conditions: a pulse length "
                "(pulse_length=<column>) or a protocol (protocol=<column>)"
            )
    if heldout:
        held = np.array([run in heldout for run, _ in tests])
        order = np.cumsum(held) - 1  # position among the held-out rows
        select, test = held & (order % 2 == 0), held & (order % 2 == 1)
        description = (
            f"held-out tables: {', '.join(r.name for r in heldout)}, rows 1, 3 ... of them "
            "selecting the terms and 2, 4 ... testing them"
        )
    else:
        if len(tests) < MIN_ROWS:
            raise DiagnosisInputError(
                f"{len(tests)} test row(s): at least {MIN_ROWS} are needed to hold one out"
            )
        select_rows, test_rows = phases.cycle_roles(len(tests))
        j = np.arange(len(tests))
        select, test = np.isin(j, select_rows), np.isin(j, test_rows)
        testing = ", ".join(t.name for (_, t), m in zip(tests, test) if m)
        description = (
            "rows held out of the fit: "
            + ", ".join(t.name for (_, t), m in zip(tests, select) if m)
            + " select the terms"
            + (f"; {testing} test them" if testing else "")
        )
    return FeatureData(
        list(runs) + list(heldout),
        tests,
        three_roles([~(select | test)], [select], [test], description),
        dt,
    )
