"""`hems bag export`: one CSV per topic that reads back to the recorded values."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from bag_helpers import T0, TOPICS, log_time, write_bag

from hems_ros.bag import load_bag
from hems_ros.bag.export import csv_name, export_csv


def hems_bag_export(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "hems_ros.cli.main", "bag", "export", *args],
        capture_output=True,
        text=True,
        timeout=120,
    )


def read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    with path.open(newline="") as handle:
        rows = list(csv.reader(handle))
    return rows[0], rows[1:]


def column(header: list[str], rows: list[list[str]], name: str) -> list[str]:
    k = header.index(name)
    return [row[k] for row in rows]


@pytest.fixture(scope="module")
def exported(tmp_path_factory) -> tuple[Path, dict[str, list], Path]:
    folder = tmp_path_factory.mktemp("export") / "run"
    written = write_bag(folder, count=120, chunk_size=4096)
    out = folder.parent / "csv"
    entries = export_csv(folder, out)
    assert sorted(e.topic for e in entries) == sorted(TOPICS)
    return folder, written, out


def test_numbers_read_back_exactly_with_times_and_stamps(exported) -> None:
    folder, written, out = exported
    header, rows = read_csv(out / csv_name("/hems/index/wire_force"))
    assert header[:3] == ["time_s", "log_time_ns", "stamp_s"]
    messages = written["/hems/index/wire_force"]
    assert len(rows) == len(messages) == 120
    k = list(TOPICS).index("/hems/index/wire_force")
    assert [int(v) for v in column(header, rows, "log_time_ns")] == [
        log_time(k, i) for i in range(120)
    ]
    # the first message of the bag is on the first topic at T0
    assert [float(v) for v in column(header, rows, "time_s")] == [
        (log_time(k, i) - T0) / 1e9 for i in range(120)
    ]
    assert [float(v) for v in column(header, rows, "force")] == [m.force for m in messages]
    assert column(header, rows, "finger") == [m.finger for m in messages]
    assert column(header, rows, "saturated") == ["1" if m.saturated else "0" for m in messages]
    assert column(header, rows, "header.frame_id") == [m.header.frame_id for m in messages]
    stamps = [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in messages]
    assert [float(v) for v in column(header, rows, "stamp_s")] == pytest.approx(stamps, abs=1e-9)

    header, rows = read_csv(out / csv_name("/hems/sim/index/state"))
    state = written["/hems/sim/index/state"]
    assert [float(v) for v in column(header, rows, "stress")] == [m.stress for m in state]
    assert [float(v) for v in column(header, rows, "martensite_fraction")] == [
        m.martensite_fraction for m in state
    ]


def test_sequences_and_nested_messages_lose_nothing(exported) -> None:
    folder, written, out = exported
    header, rows = read_csv(out / csv_name("/hems/joint_states"))
    joints = written["/hems/joint_states"]
    assert column(header, rows, "name") == [";".join(m.name) for m in joints]
    assert [[float(v) for v in cell.split(";")] for cell in column(header, rows, "position")] == [
        list(m.position) for m in joints
    ]
    assert column(header, rows, "velocity")[0] == ""  # an empty sequence in message 0

    header, rows = read_csv(out / csv_name("/hems/supervisor/status"))
    assert column(header, rows, "faults") == [
        ";".join(m.faults) for m in written["/hems/supervisor/status"]
    ]

    header, rows = read_csv(out / csv_name("/diagnostics"))
    decoded = load_bag(folder)["/diagnostics"]["status"]
    cells = column(header, rows, "status")
    assert len(cells) == len(decoded) and cells[0] == "[]"  # message 0 has no status
    for cell, message in zip(cells, written["/diagnostics"]):
        status = json.loads(cell)
        assert [s["name"] for s in status] == [s.name for s in message.status]
        assert [[kv["value"] for kv in s["values"]] for s in status] == [
            [kv.value for kv in s.values] for s in message.status
        ]


def test_fixed_length_arrays_get_one_column_per_element(tmp_path: Path) -> None:
    folder = tmp_path / "fixed"
    topics = {
        "/hems/joint_states": (
            "sensor_msgs/msg/JointState",
            lambda i: TOPICS["/hems/joint_states"][1](2 * i + 1),
        )
    }  # two joints each
    written = write_bag(folder, count=20, topics=topics)
    export_csv(folder, tmp_path / "csv")
    header, rows = read_csv(tmp_path / "csv" / csv_name("/hems/joint_states"))
    assert "position[0]" in header and "position[1]" in header
    assert [float(v) for v in column(header, rows, "position[1]")] == [
        m.position[1] for m in written["/hems/joint_states"]
    ]


def test_cli_selects_topics_reports_a_cut_bag_and_rejects_a_non_bag(
    exported, tmp_path: Path
) -> None:
    folder, written, _ = exported
    result = hems_bag_export(str(folder), "-o", str(tmp_path / "sel"), "--regex", ".*/encoder")
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in (tmp_path / "sel").iterdir()) == ["hems.index.encoder.csv"]
    assert "120 rows" in result.stdout

    mcap = folder / "run_0.mcap"
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(mcap.read_bytes()[: mcap.stat().st_size * 2 // 3])
    result = hems_bag_export(str(cut))
    assert result.returncode == 0, result.stderr
    assert "RECOVERED" in result.stderr
    header, rows = read_csv(tmp_path / "cut_csv" / csv_name("/hems/index/encoder"))
    recovered = load_bag(cut)["/hems/index/encoder"]
    assert 0 < len(rows) == len(recovered) < 120
    assert np.array_equal(
        [float(v) for v in column(header, rows, "position")], recovered["position"]
    )

    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not a bag at all")
    result = hems_bag_export(str(junk))
    assert result.returncode == 2 and "hems bag export:" in result.stderr
