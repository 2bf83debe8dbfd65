"""`hems diagnose` on bags recorded from the node graph whose unit ran a physics set with a
hidden effect (bags/README.md): the committed bag, and (slow) a bag recorded afresh."""

from __future__ import annotations

import json
import math
import re
import subprocess
from pathlib import Path

import pytest
from test_inputs import copy_bag, set_field

from hems_ros.bag import bag_info, load_bag
from hems_ros.physics.params import load_params

REPO = Path(__file__).resolve().parents[2]
BAG = REPO / "bags" / "diagnose_index_damping"
TRUTH = BAG / "physics.yaml"
ENCODER, DUTY = "/hems/index/encoder", "/hems/index/duty"
HIDDEN_DAMPING = 260.0
SUMMARY = re.compile(
    r"^named: load_damping \(b = ([\d.]+) N s/m \[[\d.]+, [\d.]+\]\); held-out position RMSE "
    r"([\d.e+-]+) mm -> "
    r"([\d.e+-]+) mm \(([+-]\d+) %\)$"
)


def diagnose(venv: Path, bag: Path, out: Path) -> subprocess.Popen:
    command = [
        str(venv / "bin" / "hems"),
        "diagnose",
        str(bag),
        "--model",
        "ch6_hems_index",
        "--out",
        str(out),
        "--quiet",
    ]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def finished(process: subprocess.Popen) -> str:
    stdout, stderr = process.communicate(timeout=240)
    assert process.returncode == 0, stdout[-2000:] + stderr[-2000:]
    return stdout.strip()


def assert_names_the_damping(summary_line: str, out: Path) -> dict:
    """The verdict the bag's hidden truth calls for, in the summary line and summary.json."""
    assert SUMMARY.match(summary_line), summary_line
    summary = json.loads((out / "summary.json").read_text())
    assert summary["verdict"] == "named"
    [named] = summary["named"]
    assert named["effect"] == "load_damping"
    b = named["parameters"]["load.damping_n_s_per_m"]["si_value"]
    assert b == pytest.approx(HIDDEN_DAMPING, rel=0.15)
    assert float(SUMMARY.match(summary_line).group(1)) == pytest.approx(b, rel=5e-3)
    gap = summary["gap"]
    assert gap["metric"] == "position RMSE" and gap["heldout_after"] <= 0.5 * gap["heldout_before"]
    assert load_params(out / "corrected.yaml").load.damping_n_s_per_m == pytest.approx(b)
    for name in ("report.md", "overlay_1.png", "residual_by_phase.png", "candidate_ranking.png"):
        assert (out / name).is_file(), name
    return summary


def test_the_truth_is_the_starting_model_with_four_times_the_damping() -> None:
    truth, model = load_params(TRUTH).to_dict(), load_params("ch6_hems_index").to_dict()
    assert "hidden truth of bags/diagnose_index_damping" in truth["description"].replace("\n", " ")
    assert (
        truth["load"]["damping_n_s_per_m"]
        == HIDDEN_DAMPING
        == 4 * model["load"]["damping_n_s_per_m"]
    )
    truth["load"]["damping_n_s_per_m"] = model["load"]["damping_n_s_per_m"]
    assert {k: v for k, v in truth.items() if k not in ("name", "description")} == {
        k: v for k, v in model.items() if k not in ("name", "description")
    }


def test_diagnose_names_the_hidden_damping_from_the_measured_topics(
    venv: Path, tmp_path: Path
) -> None:
    # the copy keeps the folder's name, so that both reports name the same run
    stripped = copy_bag(
        BAG,
        tmp_path / "measured_only" / BAG.name,
        lambda m, _: not m.topic.startswith("/hems/sim/"),
    )
    # one encoder sample with a failed reading (NaN), as a sensor fault leaves it in a bag
    failed = copy_bag(
        BAG,
        tmp_path / "one_nan" / BAG.name,
        rewrite=(ENCODER, set_field(BAG, ENCODER, "position", math.nan, {900})),
    )
    assert [t for t in bag_info(BAG).topics if t.startswith("/hems/sim/")]
    assert not [t for t in bag_info(stripped).topics if t.startswith("/hems/sim/")]
    runs = {
        "bag": diagnose(venv, BAG, tmp_path / "r"),
        "stripped": diagnose(venv, stripped, tmp_path / "s"),
        "one_nan": diagnose(venv, failed, tmp_path / "n"),
    }
    lines = {name: finished(process) for name, process in runs.items()}
    summary = assert_names_the_damping(lines["bag"], tmp_path / "r")
    # the simulation truth in the bag is not what the diagnosis found the damping with
    assert lines["stripped"] == lines["bag"]
    assert json.loads((tmp_path / "s" / "summary.json").read_text()) == summary
    # the failed sample is dropped, said so, and the verdict stays
    assert assert_names_the_damping(lines["one_nan"], tmp_path / "n")["named"][0]["parameters"][
        "load.damping_n_s_per_m"
    ]["si_value"] == pytest.approx(HIDDEN_DAMPING, rel=0.15)
    assert (
        "1 samples with /hems/index/encoder position not a number (NaN or inf) dropped"
        in (tmp_path / "n" / "report.md").read_text()
    )


def test_a_duty_outside_its_range_stops_the_diagnosis_naming_topic_and_message(
    venv: Path, tmp_path: Path
) -> None:
    broken = copy_bag(
        BAG,
        tmp_path / "overdriven",
        rewrite=(DUTY, set_field(BAG, DUTY, "duty_percent", 150.0, {2031})),
    )
    process = diagnose(venv, broken, tmp_path / "r")
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 2, stdout + stderr
    assert "Traceback" not in stderr
    assert re.search(
        r"/hems/index/duty message 2032 of \d+ \(answering the encoder sample at [\d.]+ s\) "
        r"has duty_percent = 150\.0: a duty is a number within 0-100 %",
        stderr,
    ), stderr
    assert not (tmp_path / "r" / "summary.json").exists()


# The replay applies every duty from the encoder sample it answers; the unit applies one that
# reaches it after the next sample from its arrival, and cuts the heating when commands stop
# coming for 30 ms (a stalled controller), neither of which the bag's stamps show. One 40 ms
# controller stall during a heating pulse moved the fitted damping by 9 % in a run here.
@pytest.mark.slow
@pytest.mark.graph_realtime
def test_a_fresh_recording_is_diagnosed_the_same(
    venv: Path, ros_domain_id: int, tmp_path: Path
) -> None:
    from hems_ros.client.step_figures import step_figures

    bag = tmp_path / "bag"
    # the committed bag's run with three cycles, the fewest the default held-out split takes
    command = [
        str(venv / "bin" / "hems"),
        "step",
        "--physics-config",
        str(TRUTH),
        "--cycles",
        "3",
        "--step-mm",
        "20",
        "--before-s",
        "1",
        "--step-s",
        "4",
        "--after-s",
        "5",
        "--log-level",
        "warn",
        "--record",
        str(bag),
    ]
    result = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    # three steps (runs of equal setpoints collapsed, as in tests/graph/test_step_cli.py)
    values = list(load_bag(bag, topics=["/hems/index/setpoint"])["/hems/index/setpoint"]["value"])
    assert [v for i, v in enumerate(values) if i == 0 or v != values[i - 1]] == [0.0, 0.02] * 3 + [
        0.0
    ]
    # the printed figures are the last step's, over the 4 s the tool held it (on wall time the
    # next setpoint goes out 4 s after the status confirmed this one, a little later)
    printed = re.search(
        r"step: index: rmse_mm ([\d.]+), overshoot_mm (-?[\d.]+), "
        r"steady_state_error_mm (-?[\d.]+)",
        result.stdout,
    )
    assert printed, result.stdout
    last_step = step_figures(bag, "index", 2.0, step_s=4.0)
    assert [float(v) for v in printed.groups()] == pytest.approx(list(last_step.values()), abs=5e-4)
    assert_names_the_damping(finished(diagnose(venv, bag, tmp_path / "r")), tmp_path / "r")
