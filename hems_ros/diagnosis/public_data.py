"""Published measurements of other wires, diagnosed: isobaric thermal cycles excerpted into
tests/data/public/ (its README gives sources and licences).

Each :class:`PublicStudy` is one ``hems diagnose`` call (:attr:`PublicStudy.command`): runs
fitted, runs held out (a file measured at another stress: each file holds one cycle), the
starting model and its bounds.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from hems_ros.diagnosis import inputs
from hems_ros.diagnosis.workflow import Diagnosis, diagnose


@dataclass(frozen=True)
class PublicStudy:
    key: str
    title: str
    runs: tuple[str, ...]  # files under the data folder, fitted
    heldout: tuple[str, ...]  # tested only
    columns: str
    model: str  # a config/physics name or a file under the data folder
    bounds: str | None  # file under the data folder
    source: str
    question: str

    def command(self, folder: str) -> str:
        model = self.model if "/" not in self.model else f"{folder}/{self.model}"
        parts = [
            "hems diagnose " + " ".join(f"{folder}/{r}" for r in self.runs),
            "--heldout " + " ".join(f"{folder}/{r}" for r in self.heldout),
            f"--columns {self.columns}",
            f"--model {model}",
        ]
        if self.bounds:
            parts.append(f"--bounds {folder}/{self.bounds}")
        return " ".join(parts)


STUDIES = (
    PublicStudy(
        "flexinol",
        "A Flexinol wire's isobaric cycles (maestrolab/calibrating)",
        ("flexinol/filtered_data_50MPa.txt",),
        ("flexinol/filtered_data_150MPa.txt",),
        "temperature=Temperature,strain=Strain,stress=Stress:MPa",
        "table41",
        None,
        "Pedro Leal, Texas A&M, 2019; MIT as its setup.py declares",
        "A Dynalloy Flexinol wire heated from 30 to 140 degC and cooled back on a frame that "
        "held 50 MPa within 37-66 MPa; fitted on that cycle, tested on the same wire's cycle "
        "at 150 MPa, from the dissertation's Table 4.1 wire.",
    ),
    PublicStudy(
        "nitico",
        "A NiTiCo wire's isobaric cycles (maestrolab/SMA-REACT)",
        ("nitico/50MPa.txt", "nitico/200MPa.txt"),
        ("nitico/150MPa.txt",),
        "temperature=#1,strain=#2,stress=#3:MPa",
        "nitico/model.yaml",
        "nitico/bounds.yaml",
        "Walgren, Nevin and Hartl, J. Composite Materials 2022; BSD 3-Clause",
        "A NiTiCo alloy far below the library's NiTi band, cooled from 30 to -70 degC and "
        "heated back at 50, 150 and 200 MPa; its transformation strain grows from 1.8 % at "
        "50 MPa to 3.4 % at 200 MPa, where the model's eps_L is one number. Fitted on 50 and "
        "200 MPa, tested on 150 MPa, from a starting model with its transformation "
        "temperatures and bounds of its own.",
    ),
)


def run(
    study: PublicStudy, folder: Path, progress: Callable[[str], None] | None = None
) -> Diagnosis:
    """Diagnose ``study`` on the files under ``folder`` (tests/data/public)."""
    model_name = study.model if "/" not in study.model else str(folder / study.model)
    model = inputs.model(model_name)

    def load(files: tuple[str, ...]) -> list:
        return [
            r for f in files for r in inputs.load(str(folder / f), study.columns, None, model.wire)
        ]

    bounds = inputs.bounds(folder / study.bounds) if study.bounds else None
    return diagnose(load(study.runs), load(study.heldout), model, bounds=bounds, progress=progress)
