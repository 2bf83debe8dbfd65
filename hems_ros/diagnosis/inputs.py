"""What ``hems diagnose`` is given on its command line, checked and loaded: the starting
model with the run's conditions, the candidate names, the runs and the report folder.

Every problem is a :class:`DiagnosisInputError` whose message is one line.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Sequence
from pathlib import Path
from typing import overload

import yaml

from hems_ros.diagnosis import bagload, candidates, csvload
from hems_ros.diagnosis.runs import DiagnosisInputError, FeatureRun, Run
from hems_ros.physics.params import ParamError, UnitParams, WireGeometry, load_params
from hems_ros.physics.yamlload import load_yaml


def model(name: str, conditions: Path | None = None, overrides: Sequence[str] = ()) -> UnitParams:
    """The starting model: a named set or YAML file, the run's conditions,
    ``KEY=VALUE`` overrides."""
    try:
        params = load_params(name)
    except FileNotFoundError:
        raise DiagnosisInputError(f"--model {name}: no such file") from None
    except ParamError as error:
        raise DiagnosisInputError(f"--model {name}: {error}") from None
    if conditions is not None:
        params = _with_conditions(params, conditions)
    changes = {}
    for item in overrides:
        key, sep, text = item.partition("=")
        if not sep or not key:
            raise DiagnosisInputError(
                f"--set {item!r}: expected KEY=VALUE, e.g. load.pretension_n=20"
            )
        changes[key.strip()] = _value(text)
    try:
        return params.replace(changes) if changes else params
    except ParamError as error:
        raise DiagnosisInputError(f"--set: {error}") from None


def _value(text: str):
    """A number as Python reads it (YAML 1.1 reads 6.89e6 as a string), else YAML (true, a name)."""
    try:
        return float(text) if any(c in text for c in ".eEn") else int(text)
    except ValueError:
        return yaml.safe_load(text)


def _mapping(option: str, path: Path, expected: str) -> dict:
    """The YAML mapping in the file an option names; DiagnosisInputError otherwise."""
    try:
        data = load_yaml(Path(path).read_text())
    except OSError as error:
        raise DiagnosisInputError(f"{option} {path}: {error.strerror or error}") from None
    except yaml.YAMLError as error:
        raise DiagnosisInputError(
            f"{option} {path}: not valid YAML ({str(error).splitlines()[0]})"
        ) from None
    if not isinstance(data, dict) or not data:
        raise DiagnosisInputError(f"{option} {path}: expected {expected}")
    return data


def _with_conditions(params: UnitParams, path: Path) -> UnitParams:
    """``params`` with the groups and keys a partial physics YAML gives."""
    try:
        return params.replace(dict(rig(path)))
    except (ParamError, TypeError) as error:
        raise DiagnosisInputError(f"--conditions {path}: {error}") from None


def rig(path: Path) -> tuple[tuple[str, object], ...]:
    """A conditions file (a partial physics YAML) as (dotted key, value) pairs."""
    data = _mapping("--conditions", path, "a mapping of parameter groups")
    pairs: list[tuple[str, object]] = []
    for group, values in data.items():
        if isinstance(values, dict):
            pairs += [(f"{group}.{key}", value) for key, value in values.items()]
        else:
            pairs.append((group, values))
    return tuple(pairs)


def per_run(option: str, given: list, n_runs: int) -> list:
    """An option given once for every run, or once per run in order; None where not given."""
    if not given:
        return [None] * n_runs
    if len(given) == 1:
        return list(given) * n_runs
    if len(given) != n_runs:
        raise DiagnosisInputError(
            f"{option} given {len(given)} times for {n_runs} run(s): give it once for all, "
            "or once per RUN then --heldout RUN, in order"
        )
    return list(given)


@overload
def on_rig(runs: list[Run], conditions: Path, model: UnitParams) -> list[FeatureRun]: ...


@overload
def on_rig(runs: list[Run], conditions: Path | None, model: UnitParams) -> Sequence[Run]: ...


def on_rig(runs: list[Run], conditions: Path | None, model: UnitParams) -> Sequence[Run]:
    """The runs of one RUN argument, tables of tests set on the rig its --conditions give."""
    if conditions is None:
        return runs
    pairs = rig(conditions)
    tables: list[FeatureRun] = []
    for run in runs:
        if not isinstance(run, FeatureRun):
            raise DiagnosisInputError(
                f"--conditions {conditions} for {run.name}: a rig per run applies to tables of "
                "tests only; give one --conditions for every run of a time series"
            )
        tables.append(run)
    try:
        model.replace(dict(pairs))
    except (ParamError, TypeError) as error:
        raise DiagnosisInputError(f"--conditions {conditions}: {error}") from None
    return [dataclasses.replace(table, rig=pairs) for table in tables]


def bounds(path: Path | None) -> dict[str, object]:
    """The ``--bounds`` file: parameter key -> ``[lower, upper]`` or
    ``{around_model: [below, above]}``, SI units (checked against the library by
    ``candidates.with_bounds``)."""
    if path is None:
        return {}
    return _mapping(
        "--bounds",
        path,
        "a mapping of parameter keys to [lower, upper], e.g. kinetics.as0_c: [40, 75]",
    )


def candidate_names(text: str | None) -> list[str] | None:
    if text is None:
        return None
    names = [n.strip() for n in text.split(",") if n.strip()]
    unknown = [n for n in names if n not in candidates.BY_NAME]
    if unknown or not names:
        raise DiagnosisInputError(
            f"--candidates: unknown {', '.join(unknown) or '(none given)'} "
            f"(known: {', '.join(candidates.BY_NAME)})"
        )
    return names


def is_bag(path: Path) -> bool:
    return path.suffix == ".mcap" or (
        path.is_dir() and (any(path.glob("*.mcap")) or (path / "metadata.yaml").exists())
    )


def load(text: str, columns: str | None, fingers: str | None, wire: WireGeometry) -> list[Run]:
    """The runs in one RUN argument: every finger of a bag, or one table (a load column
    turned into stress, or a stress into force, over the model wire's cross-section; an
    extension into strain over its length)."""
    path = Path(text)
    if not path.exists():
        raise DiagnosisInputError(f"{text}: no such file or folder")
    if is_bag(path):
        chosen = [f.strip() for f in fingers.split(",") if f.strip()] if fingers else None
        return list(bagload.load_bag_runs(path, chosen))
    if path.is_dir():
        raise DiagnosisInputError(f"{text}: a folder that is not a bag (no .mcap file in it)")
    if not columns:
        raise DiagnosisInputError(
            f"{text}: a table needs --columns quantity=column[:unit],... "
            "(e.g. time=t:s,current=I:A,displacement=x:mm)"
        )
    return [
        csvload.load_table(
            path, columns, cross_section_m2=wire.cross_section_m2, gauge_length_m=wire.length_m
        )
    ]


def stem(text: str) -> str:
    path = Path(text.rstrip("/"))
    return path.stem if path.suffix else path.name


ARCHIVE_TABLE = "archive.md"  # what marks a folder of per-run reports (hems diagnose --each)


def check_output(out: Path) -> None:
    """Refuse a report folder that would overwrite something other than a report."""
    is_report = (out / "summary.json").is_file() or (out / ARCHIVE_TABLE).is_file()
    if out.exists() and (not out.is_dir() or (any(out.iterdir()) and not is_report)):
        raise DiagnosisInputError(f"--out {out}: exists and is not a diagnosis report folder")
    parent = out.resolve().parent
    while not parent.exists():
        parent = parent.parent
    if not os.access(parent, os.W_OK):
        raise DiagnosisInputError(f"--out {out}: cannot write under {parent}")
