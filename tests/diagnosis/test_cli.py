"""``hems diagnose`` as a user runs it: help, the candidate list, every bad input refused with
exit 2 and one line, and a good table run that writes a complete report folder."""

from __future__ import annotations

import argparse
import json
import os
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from hems_ros.bag import BagWriter, iter_messages
from hems_ros.cli import diagnose
from hems_ros.diagnosis import features, inputs, suite
from hems_ros.diagnosis.runs import FeatureTest
from hems_ros.physics.params import load_params

REPO = Path(__file__).resolve().parents[2]
HEMS = REPO / ".venv" / "bin" / "hems"
COLUMNS = "time=t:s,duty=d:%,displacement=x:mm,force=F:N"
TIMEOUT_S = 180


def hems(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    return subprocess.run(
        [str(HEMS), *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=TIMEOUT_S
    )


def _write_run(path: Path, t: np.ndarray, duty: np.ndarray, x: np.ndarray, f: np.ndarray) -> Path:
    lines = ["t,d,x,F"] + [
        f"{a:.4f},{b:g},{c * 1e3:.3f},{e:.2f}" for a, b, c, e in zip(t, duty, x, f)
    ]
    path.write_text("\n".join(lines) + "\n")
    return path


PULSES = "name=name,pulse_length=p:s,current=i:A,peak_displacement=x:mm"


def _write_pulses(path: Path, truth=None) -> None:
    """Four current pulses and the peak displacement ``truth`` reaches (4.0 mm by default)."""
    rows = [(1.4, 4.0), (1.8, 4.0), (2.2, 3.5), (2.6, 3.5)]
    if truth is None:
        peaks = [4.0] * len(rows)
    else:
        shells = [
            FeatureTest(f"r{k}", {"pulse_s": p, "current_a": a}, {})
            for k, (p, a) in enumerate(rows)
        ]
        peaks = [
            f["peak_displacement"] * 1e3
            for f in features._pulse_figures([truth], shells, features.PULSE_DT)
        ]
    lines = ["name,p,i,x"] + [
        f"r{k},{p},{a},{x:.6f}" for k, ((p, a), x) in enumerate(zip(rows, peaks))
    ]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    """A work folder with a good run (40 s of pulses, 400 N s/m of hidden load damping) and
    broken copies of it."""
    root = tmp_path_factory.mktemp("diagnose_cli")
    case = next(c for c in suite.CASES if c.name == "load_damping")
    run = suite.measure(case, suite.pulse_profile()[:4000], "low", 0, load_params("table41"))
    t, d, x, f = run.time, run.drive_values, run.outputs["position"], run.outputs["wire_force"]
    _write_run(root / "good.csv", t, d, x, f)
    text = (root / "good.csv").read_text().splitlines()
    # a duty that is not a number: an input, refused (a measured nan drops its row)
    (root / "nan.csv").write_text("\n".join(text[:6] + ["0.0500,nan,0,12.00"] + text[7:]) + "\n")
    (root / "bounds.yaml").write_text("kinetics.as1_c: [1, 2]\n")
    (root / "backwards.csv").write_text("\n".join(text[:11] + [text[9]] + text[12:]) + "\n")
    (root / "short.csv").write_text("\n".join(text[:11]) + "\n")
    _write_run(root / "one_pulse.csv", t[:1000], d[:1000], x[:1000], f[:1000])
    # read by a larger load cell than the model's 50 N sensor
    _write_run(root / "heavy.csv", t, d, x, f + 40.0)
    with BagWriter(root / "empty_bag"):
        pass
    # a bag of the simulation's truth only: no measured topic in it
    with BagWriter(root / "sim_bag") as writer:
        for m in iter_messages(REPO / "bags" / "ch5_step_index", topics=["/hems/sim/index/state"]):
            writer.write_copy(m)
    (root / "bad_conditions.yaml").write_text("load: {pretension_n: [1, 2\n")
    (root / "bad_model.yaml").write_text("load:\n  stiffness_n_per_m: -5\n")
    (root / "list.yaml").write_text("- load\n- ambient\n")
    (root / "rig.yaml").write_text(
        "load: {kind: hanging_mass, mass_kg: 3.0, stiffness_n_per_m: 0}\n"
    )
    (root / "bad_rig.yaml").write_text("load: {mass: 3}\n")
    _write_pulses(root / "pulses.csv")
    (root / "taken").mkdir()
    (root / "taken" / "notes.txt").write_text("keep me\n")
    return root


def test_help_and_candidate_list(folder: Path) -> None:
    result = hems("diagnose", "--help", cwd=folder)
    assert result.returncode == 0 and "usage: hems diagnose" in result.stdout
    assert "--list-candidates" in result.stdout and "quantity=column[:unit]" in result.stdout
    result = hems("diagnose", "--list-candidates", cwd=folder)
    assert result.returncode == 0 and result.stderr == ""
    lines = result.stdout.splitlines()
    assert len(lines) == 3 * 17
    assert (
        lines[0]
        == "heating_temperatures (recalibration): austenite transformation temperatures As0, Af0"
    )
    assert "    b 65..3000 N s/m [load.damping_n_s_per_m]; changes transformation, cooling" in lines


# (case, arguments, what the message must say): as processes, the way a user meets them; one
# of each kind of input (table, bag, model, conditions), since each process spends seconds
# importing
BAD = [
    ("missing file", ["absent.csv", "--columns", COLUMNS], "absent.csv: no such file or folder"),
    ("table without --columns", ["good.csv"], "good.csv: a table needs --columns"),
    (
        "nan",
        ["nan.csv", "--columns", COLUMNS],
        "nan.csv: row 7, column d: 'nan' is not a finite number",
    ),
    (
        "bounds of no parameter",
        ["good.csv", "--columns", COLUMNS, "--bounds", "bounds.yaml"],
        "--bounds: kinetics.as1_c: not a parameter of the candidates",
    ),
    (
        "bag of other topics",
        ["sim_bag"],
        "sim_bag: no finger has duty and encoder messages in the bag (read: " "nothing)",
    ),
    (
        "model",
        ["good.csv", "--columns", COLUMNS, "--model", "nosuch"],
        "--model nosuch: no parameter set named 'nosuch'",
    ),
    (
        "conditions yaml",
        ["good.csv", "--columns", COLUMNS, "--conditions", "bad_conditions.yaml"],
        "--conditions bad_conditions.yaml: not valid YAML",
    ),
]
# the rest in this process, through the verb's own parser and run()
MORE = [
    ("no run", [], "no RUN given"),
    (
        "force beyond the model's sensor",
        ["heavy.csv", "--columns", COLUMNS],
        "heavy: the wire force reaches 82.99 N (100% of the samples), above the model's force "
        "sensor range of 50 N (force_sensor.range_max_n)",
    ),
    (
        "unknown column",
        ["good.csv", "--columns", "time=t,duty=d,displacement=zz"],
        "column 'zz' (for displacement) is not in the header",
    ),
    (
        "unknown unit",
        ["good.csv", "--columns", "time=t,duty=d,displacement=x:furlong"],
        "unknown unit 'furlong' for displacement (known: m, mm, um, in)",
    ),
    (
        "unknown quantity",
        ["good.csv", "--columns", "time=t,duty=d,speed=x"],
        "unknown quantity 'speed'",
    ),
    (
        "time backwards",
        ["backwards.csv", "--columns", COLUMNS],
        "backwards.csv: row 12: time 0.08 s is not after row 11's 0.09 s",
    ),
    ("too short", ["short.csv", "--columns", COLUMNS], "short.csv: 10 samples are too few"),
    # two pulses (the count says 1: the first cycle is lost, see test_phases.py)
    (
        "too few cycles",
        ["one_pulse.csv", "--columns", COLUMNS],
        "too short to hold data out: one_pulse ",
    ),
    (
        "too few cycles, advice",
        ["one_pulse.csv", "--columns", COLUMNS],
        "cycle(s); a run needs at least 3 actuation cycles, or give --heldout RUN",
    ),
    ("empty bag", ["empty_bag"], "empty_bag: no finger has duty and encoder messages in the bag"),
    (
        "model file",
        ["good.csv", "--columns", COLUMNS, "--model", "absent.yaml"],
        "--model absent.yaml: no such file",
    ),
    (
        "model values",
        ["good.csv", "--columns", COLUMNS, "--model", "bad_model.yaml"],
        "load.stiffness_n_per_m = -5.0: must be >= 0",
    ),
    (
        "candidates",
        ["good.csv", "--columns", COLUMNS, "--candidates", "load_damping,gremlins"],
        "--candidates: unknown gremlins (known: heating_temperatures,",
    ),
    (
        "set malformed",
        ["good.csv", "--columns", COLUMNS, "--set", "load.pretension_n"],
        "--set 'load.pretension_n': expected KEY=VALUE",
    ),
    (
        "set unknown",
        ["good.csv", "--columns", COLUMNS, "--set", "load.colour=red"],
        "--set: replace: unknown parameter load.colour",
    ),
    (
        "set value",
        ["good.csv", "--columns", COLUMNS, "--set", "load.pretension_n=lots"],
        "load.pretension_n = 'lots': must be a number",
    ),
    (
        "conditions missing",
        ["good.csv", "--columns", COLUMNS, "--conditions", "absent.yaml"],
        "--conditions absent.yaml: No such file or directory",
    ),
    (
        "conditions not a mapping",
        ["good.csv", "--columns", COLUMNS, "--conditions", "list.yaml"],
        "--conditions list.yaml: expected a mapping of parameter groups",
    ),
    (
        "heldout missing",
        ["good.csv", "--columns", COLUMNS, "--heldout", "absent.csv"],
        "absent.csv: no such file or folder",
    ),
    (
        "columns twice for three runs",
        ["good.csv", "good.csv", "good.csv", "--columns", COLUMNS, "--columns", COLUMNS],
        "--columns given 2 times for 3 run(s): give it once for all, or once per RUN",
    ),
    (
        "a rig for a time series",
        ["good.csv", "--heldout", "good.csv", "--columns", COLUMNS]
        + ["--conditions", "rig.yaml", "--conditions", "rig.yaml"],
        "--conditions rig.yaml for good: a rig per run applies to tables of tests only",
    ),
    (
        "a rig that names no parameter",
        ["pulses.csv", "pulses.csv", "--columns", PULSES]
        + ["--conditions", "rig.yaml", "--conditions", "bad_rig.yaml"],
        "--conditions bad_rig.yaml: replace: unknown parameter load.mass",
    ),
]


def _out(name: str) -> str:
    return "out_" + name.replace(" ", "_")


def _assert_refused(folder: Path, name: str, code: int, out: str, err: str, message: str) -> None:
    assert code == 2, err
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("hems diagnose: "), err
    assert message in lines[0]
    assert not (folder / _out(name)).exists()
    assert not (folder / "results").exists()
    assert not list(folder.glob(".out_*"))  # no partial report either


@pytest.fixture(scope="module")
def refused(folder: Path) -> dict[str, subprocess.CompletedProcess]:
    """Every bad case, two at a time (each process spends seconds importing)."""

    def one(case):
        name, args, _ = case
        return name, hems("diagnose", *args, "--quiet", "--out", _out(name), cwd=folder)

    with ThreadPoolExecutor(max_workers=2) as pool:
        return dict(pool.map(one, BAD))


@pytest.mark.parametrize("name, args, message", BAD, ids=[b[0] for b in BAD])
def test_bad_input_exits_2_with_one_line(
    folder: Path, refused, name: str, args, message: str
) -> None:
    result = refused[name]
    _assert_refused(folder, name, result.returncode, result.stdout, result.stderr, message)


@pytest.mark.parametrize("name, args, message", MORE, ids=[b[0] for b in MORE])
def test_more_bad_input_exits_2_with_one_line(
    folder: Path, monkeypatch, capsys, name: str, args, message: str
) -> None:
    parser = argparse.ArgumentParser(prog="hems")
    diagnose.register(parser.add_subparsers())
    monkeypatch.chdir(folder)
    parsed = parser.parse_args(["diagnose", *args, "--quiet", "--out", _out(name)])
    code = parsed.func(parsed)
    captured = capsys.readouterr()
    _assert_refused(folder, name, code, captured.out, captured.err, message)


def test_out_that_is_not_a_report_is_refused(folder: Path) -> None:
    result = hems(
        "diagnose", "good.csv", "--columns", COLUMNS, "--quiet", "--out", "taken", cwd=folder
    )
    assert result.returncode == 2
    assert (
        result.stderr == "hems diagnose: --out taken: exists and is not a diagnosis report folder\n"
    )
    assert [p.name for p in (folder / "taken").iterdir()] == ["notes.txt"]
    assert (folder / "taken" / "notes.txt").read_text() == "keep me\n"


@pytest.fixture(scope="module")
def report(folder: Path) -> tuple[subprocess.CompletedProcess, Path]:
    out = folder / "report"
    return hems(
        "diagnose", "good.csv", "--columns", COLUMNS, "--quiet", "--out", str(out), cwd=folder
    ), out


def test_good_run_prints_one_summary_line(report) -> None:
    result, _ = report
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""  # --quiet: no progress
    lines = result.stdout.splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("named: load_damping (b = 40")
    assert "held-out position RMSE" in lines[0] and lines[0].endswith("(-100 %)")


def test_good_run_writes_the_report_folder(report) -> None:
    _, out = report
    names = sorted(p.name for p in out.iterdir())
    assert names == [
        "candidate_ranking.png",
        "corrected.yaml",
        "overlay_1.png",
        "report.md",
        "residual_by_phase.png",
        "summary.json",
    ]
    for png in ("candidate_ranking.png", "overlay_1.png", "residual_by_phase.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(out.parent.glob(".report.partial-*"))
    summary = json.loads((out / "summary.json").read_text())
    assert {"verdict", "named", "recalibrated", "unexplained", "gap"} <= set(summary)
    assert (
        summary["verdict"] == "named"
        and summary["recalibrated"] == {}
        and summary["unexplained"] == []
    )
    (named,) = summary["named"]
    assert named["effect"] == "load_damping"
    b = named["parameters"]["load.damping_n_s_per_m"]
    assert (
        b["symbol"] == "b" and b["unit"] == "N s/m" and b["value"] == pytest.approx(400.0, rel=0.02)
    )
    gap = summary["gap"]
    assert set(gap) == {
        "metric",
        "unit",
        "train_before",
        "train_after",
        "heldout_before",
        "heldout_after",
        "noise_floor",
        "heldout_beyond_noise_before",
        "heldout_beyond_noise_after",
    }
    assert gap["heldout_beyond_noise_after"] <= gap["heldout_after"] and gap["noise_floor"] > 0
    assert gap["metric"] == "position RMSE" and gap["unit"] == "mm"
    assert gap["heldout_before"] > 0.3 and gap["heldout_after"] < 0.005
    assert gap["train_before"] > 0.3 and gap["train_after"] < 0.005
    corrected = load_params(out / "corrected.yaml")
    assert corrected.name == "table41_corrected"
    assert corrected.load.damping_n_s_per_m == pytest.approx(b["si_value"], rel=1e-12)
    assert corrected.replace(
        {
            "load.damping_n_s_per_m": 65.0,
            "name": "table41",
            "description": load_params("table41").description,
        }
    ) == load_params("table41")
    text = (out / "report.md").read_text()
    assert text.startswith("# Diagnosis: table41 against the measurement\n")
    assert "| load.damping_n_s_per_m | 65 | 40" in text
    for png in ("candidate_ranking.png", "overlay_1.png", "residual_by_phase.png"):
        assert f"]({png})" in text


def test_running_again_replaces_the_report(folder: Path, report) -> None:
    _, out = report
    before = json.loads((out / "summary.json").read_text())
    (out / "stale.txt").write_text("from the first run\n")
    result = hems(
        "diagnose",
        "good.csv",
        "--columns",
        COLUMNS,
        "--quiet",
        "--candidates",
        "encoder_gain",
        "--out",
        str(out),
        cwd=folder,
    )
    assert result.returncode == 0, result.stderr
    assert not (out / "stale.txt").exists()
    after = json.loads((out / "summary.json").read_text())
    assert before["verdict"] == "named" and after["verdict"] == "unexplained"
    assert [r["candidate"] for r in after["ranking"]] == ["encoder_gain"]
    assert result.stdout.startswith("unexplained: the residual in ")
    assert load_params(out / "corrected.yaml").load.damping_n_s_per_m == 65.0


def test_tables_from_two_rigs_recalibrate_one_wire(tmp_path: Path) -> None:
    """Pulse tables of one wire (As0 80 degC) on a 900 N/m spring and under a 3 kg mass, each
    given its rig: one As0 meets both."""
    wire = load_params("table41").replace({"kinetics.as0_c": 80.0, "kinetics.af0_c": 90.0})
    rigs = {
        "spring": "load: {kind: bias_spring, mass_kg: 0, stiffness_n_per_m: 900, pretension_n: 12}",
        "mass": "load: {kind: hanging_mass, mass_kg: 3.0, stiffness_n_per_m: 0, pretension_n: 0}",
    }
    args = []
    for name, text in rigs.items():
        (tmp_path / f"{name}.yaml").write_text(text + "\n")
        rig = inputs.rig(tmp_path / f"{name}.yaml")
        _write_pulses(tmp_path / f"{name}.csv", wire.replace(dict(rig)))
        args += ["--conditions", f"{name}.yaml"]
    result = hems(
        "diagnose",
        "spring.csv",
        "mass.csv",
        "--columns",
        PULSES,
        *args,
        "--candidates",
        "heating_temperatures",
        "--quiet",
        "--out",
        "joint",
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "joint" / "summary.json").read_text())
    assert summary["verdict"] == "recalibrated", result.stdout
    assert summary["recalibrated"]["kinetics.as0_c"]["value"] == pytest.approx(80.0, abs=0.5)
    # both tables met (on one rig for both, As0 lands near 78.6 degC with 3.6 mm left)
    assert summary["gap"]["heldout_after"] < 0.01


def test_an_archive_is_diagnosed_run_by_run_and_together_on_a_cluster(folder: Path) -> None:
    (folder / "second").mkdir(exist_ok=True)
    (folder / "second" / "good.csv").write_text((folder / "good.csv").read_text())
    common = ["good.csv", "second/good.csv", "--columns", COLUMNS, "--candidates"]
    common += ["load_damping,encoder_gain", "--each"]
    cluster = hems("diagnose", *common, "--workers", "2", "--out", "archive", cwd=folder)
    assert cluster.returncode == 0, cluster.stderr[-3000:]
    lines = cluster.stdout.splitlines()
    assert [line.split(": ", 1)[0] for line in lines] == ["good", "good-2", "all"]
    assert all(line.split(": ", 2)[1] == "named" for line in lines), lines
    assert "2 workers at tcp://127.0.0.1:" in cluster.stderr
    table = (folder / "archive" / "archive.md").read_text()
    assert "| [good-2](good-2/report.md) | named: load_damping" in table
    serial = hems("diagnose", *common, "--scheduler", "serial", "--out", "serial", cwd=folder)
    assert serial.returncode == 0 and serial.stdout == cluster.stdout
    for key in ("good", "good-2", "all"):
        assert json.loads((folder / "archive" / key / "summary.json").read_text()) == json.loads(
            (folder / "serial" / key / "summary.json").read_text()
        )
    again = hems("diagnose", *common, "--scheduler", "serial", "--out", "serial", cwd=folder)
    assert again.returncode == 0 and "resuming: 3 of 3 tasks already done" in again.stderr
    assert again.stdout == cluster.stdout
