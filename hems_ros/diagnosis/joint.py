"""The dissertation's three tables diagnosed together: one wire for chapters 3, 5 and 6.

Each table runs on its own rig (config/measurements/*_rig.yaml) from the Table 4.1 wire, whose
stress slopes lie within NiTi's band; then each table alone refits the joint model's terms
(which chapters pull a parameter apart), and each calibrated set is weighed against the same
set with only its stress slopes refitted within that band (which figures need the calibrated
sets' 33.5 MPa/degC, by how much).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from hems_ros.diagnosis import candidates, csvload, features, fit, inputs, intervals
from hems_ros.diagnosis.dissertation import STUDIES, SheathCheck, Study, sheath_check
from hems_ros.diagnosis.runs import FeatureRun
from hems_ros.diagnosis.workflow import Diagnosis, diagnose
from hems_ros.paths import config_path
from hems_ros.physics.params import load_params

#: The joint diagnosis starts from the dissertation's own wire, every slope within NiTi's band.
JOINT_MODEL = "table41"


def joint_tables() -> list[FeatureRun]:
    """Every study's table, each on its own rig (what :func:`joint_command` loads)."""
    folder = config_path("measurements")
    model = inputs.model(JOINT_MODEL)
    return [
        run
        for s in STUDIES
        for run in inputs.on_rig(
            [csvload.load_table(folder / s.table, s.columns, name=s.key)], folder / s.rig, model
        )
    ]


def joint_command() -> str:
    """The ``hems diagnose`` call of the joint diagnosis: --columns and --conditions per table."""
    return " ".join(
        ["hems diagnose"]
        + [f"config/measurements/{s.table}" for s in STUDIES]
        + [f"--columns {s.columns}" for s in STUDIES]
        + [f"--model {JOINT_MODEL}"]
        + [f"--conditions config/measurements/{s.rig}" for s in STUDIES]
    )


def run_joint(tables: list[FeatureRun], progress: Callable[[str], None] | None = None) -> Diagnosis:
    """One wire (and sheath) for the three tables together, from :data:`JOINT_MODEL`."""
    return diagnose(tables, [], inputs.model(JOINT_MODEL), progress=progress)


#: Each study with its table on its rig and that table prepared alone.
Alone = list[tuple[Study, FeatureRun, features.FeatureData]]


@dataclass(frozen=True)
class FigureMiss:
    """How far a model misses one figure of one table: the RMS over its rows of the miss in
    units of the figure's assumed uncertainty (``features.uncertainty``)."""

    study: Study
    figure: str
    calibrated: float  # the calibrated set of the study's rig (C_M = C_A = 33.5 MPa/degC)
    slopes_in_bounds: float  # the same set, its stress slopes refitted within NiTi's band
    joint: float  # the joint corrected model on the study's rig


def in_bounds_slopes(study: Study, data: features.FeatureData) -> fit.Fit:
    """The study's calibrated set with C_A, C_M refitted to its table (``data``) within the
    library's bounds (NiTi's band), everything else as calibrated."""
    [found] = fit.fit_structures(
        data, load_params(study.calibrated), [(candidates.BY_NAME["stress_slopes"],)], {}
    )
    return found


def figure_misses(d: Diagnosis, slopes: dict[str, fit.Fit], alone: Alone) -> list[FigureMiss]:
    """Every study's figures: the calibrated set, the same with its slopes in bounds
    (``slopes``, by study key), and the joint corrected model."""
    out = []
    for study, table, data in alone:
        rig = dict(table.rig)
        calibrated, in_bounds, joint_model = data.predict(
            [
                load_params(study.calibrated).replace(rig),
                slopes[study.key].params.replace(rig),
                d.corrected.replace(rig),
            ]
        )
        for figure in data.channels:
            out.append(
                FigureMiss(
                    study,
                    figure,
                    _miss(data, calibrated, figure),
                    _miss(data, in_bounds, figure),
                    _miss(data, joint_model, figure),
                )
            )
    return out


def _miss(data: features.FeatureData, prediction, figure: str) -> float:
    r = [
        (prediction.outputs[j].get(figure, math.nan) - t.figures[figure])
        / features.uncertainty(figure, t.figures[figure])
        for j, (_, t) in enumerate(data.tests)
        if figure in t.figures
    ]
    return float(np.sqrt(np.mean(np.square(r)))) if r else math.nan


@dataclass(frozen=True)
class Pull:
    """Where one study's table alone takes one candidate, on top of the joint corrected model:
    each parameter's value and 95 % interval, and those that ended on a published bound."""

    study: Study
    candidate: str
    values: dict[str, tuple[float, float, float]]  # key -> (value, lower, upper), SI
    pinned: tuple[str, ...]


def pulls(d: Diagnosis, alone: Alone, progress: Callable[[str], None] | None = None) -> list[Pull]:
    """Every candidate of the joint model, and the stress slopes, refitted on each table alone:
    chapters whose intervals do not overlap pull that parameter apart."""
    names = [c.name for c in d.search.final.structure if c.kind != "timing"]
    names += [n for n in ("stress_slopes",) if n not in names]
    out = []
    for study, _, data in alone:
        for name in names:
            if progress:
                progress(f"{study.key}: {name} on this table alone")
            [found] = fit.fit_structures(data, d.corrected, [(candidates.BY_NAME[name],)], {})
            bounds = intervals.estimate(data, d.corrected, found)
            assert bounds is not None  # the fit has the candidate's terms
            values = {}
            for key, value in zip(bounds.keys, bounds.values):
                low, high = bounds.of(key)
                values[key] = (float(value), low, high)
            out.append(Pull(study, name, values, tuple(found.pinned)))
    return out


def apart(pulled: list[Pull]) -> list[tuple[str, Pull, Pull]]:
    """(parameter key, pull, pull) of two tables whose 95 % intervals of it do not overlap."""
    out = []
    for i, a in enumerate(pulled):
        for b in pulled[i + 1 :]:
            if a.candidate != b.candidate or a.study == b.study:
                continue
            for key, (_, low_a, high_a) in a.values.items():
                _, low_b, high_b = b.values[key]
                if high_a < low_b or high_b < low_a:
                    out.append((key, a, b))
    return out


@dataclass(frozen=True)
class Joint:
    """The joint diagnosis, what each table alone makes of its terms, each calibrated set with
    its stress slopes refitted within NiTi's band, every figure of the three models, and the
    joint model's chapter 3 sheath facts."""

    diagnosis: Diagnosis
    pulls: list[Pull]
    slopes: dict[str, fit.Fit]  # study key -> calibrated set, slopes refitted in bounds
    misses: list[FigureMiss]
    sheath: SheathCheck

    @property
    def need_the_slope(self) -> list[FigureMiss]:
        """Figures the calibrated set meets better than the same set with its slopes in bounds."""
        return [m for m in self.misses if m.slopes_in_bounds > m.calibrated]

    @property
    def worse(self) -> list[FigureMiss]:
        """Figures the calibrated sets meet better than the joint in-bounds model."""
        return [m for m in self.misses if m.joint > m.calibrated]


def joint(progress: Callable[[str], None] | None = None) -> Joint:
    say = progress or (lambda message: None)
    tables = joint_tables()
    d = run_joint(tables, progress)
    alone = [(s, t, features.prepare([t], [])) for s, t in zip(STUDIES, tables)]
    slopes = {}
    for study, _, data in alone:
        say(f"{study.calibrated}: its stress slopes refitted within NiTi's band")
        slopes[study.key] = in_bounds_slopes(study, data)
    return Joint(
        d, pulls(d, alone, progress), slopes, figure_misses(d, slopes, alone), sheath_check(d)
    )
