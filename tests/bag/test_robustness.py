"""Damaged bags: cut mid-chunk, not MCAP, bad header, corrupt chunk, unknown schema."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from bag_helpers import write_bag

from hems_ros.bag import BagFormatError, BagWarning, bag_info, load_bag
from hems_ros.bag.mcapscan import MAGIC


def hems_bag_info(path: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "hems_ros.cli.main", "bag", "info", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
    )


@pytest.fixture
def finished(tmp_path: Path) -> tuple[Path, dict]:
    folder = tmp_path / "run"
    written = write_bag(folder, count=400, chunk_size=8192)
    return folder / "run_0.mcap", written


def test_cut_in_the_middle_of_a_chunk(finished, tmp_path: Path) -> None:
    path, written = finished
    from mcap.reader import make_reader

    with open(path, "rb") as stream:
        indexes = make_reader(stream).get_summary().chunk_indexes
    assert len(indexes) >= 6
    victim = indexes[len(indexes) // 2]
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[: victim.chunk_start_offset + victim.chunk_length // 2])
    complete_before = load_bag(path)
    end_of_previous = indexes[len(indexes) // 2 - 1].message_end_time

    bag = load_bag(cut)
    report = bag.reports[0]
    assert not bag.complete and report.stopped_at == victim.chunk_start_offset
    assert "inside a chunk" in report.reason
    for topic, data in bag.topics.items():
        full = complete_before[topic]
        assert len(data) >= np.count_nonzero(
            full.log_time_ns <= end_of_previous
        )  # every finished chunk
        assert np.array_equal(data.log_time_ns, full.log_time_ns[: len(data)])  # a clean prefix
    wire = bag["/hems/index/wire_force"]
    assert list(wire["sequence"]) == list(range(len(wire)))
    assert report.messages == sum(len(d) for d in bag.topics.values())

    result = hems_bag_info(cut)
    assert result.returncode == 0
    assert f"recovered {report.messages} messages" in result.stdout
    assert f"stopped at byte {victim.chunk_start_offset}" in result.stdout


def test_cut_at_every_kind_of_place_never_raises(finished, tmp_path: Path) -> None:
    path, _ = finished
    data = path.read_bytes()
    previous = -1
    for length in sorted(
        {100, 300, 1000, len(data) // 3, len(data) // 2, len(data) - 200, len(data) - 9}
    ):
        cut = tmp_path / f"cut{length}.mcap"
        cut.write_bytes(data[:length])
        info = bag_info(cut)
        assert not info.reports[0].complete
        assert info.message_count >= previous
        previous = info.message_count


@pytest.mark.parametrize(
    "content, message",
    [
        (b"", "not an MCAP file"),
        (b"PK\x03\x04 a zip file, not a bag", "not an MCAP file"),
        (MAGIC + b"\x07" + bytes(8), "bad MCAP header record"),
        (MAGIC + b"\x01" + (10**6).to_bytes(8, "little") + b"short", "bad MCAP header record"),
    ],
)
def test_not_mcap_or_bad_header(tmp_path: Path, content: bytes, message: str) -> None:
    path = tmp_path / "broken.mcap"
    path.write_bytes(content)
    with pytest.raises(BagFormatError, match=message):
        load_bag(path)
    result = hems_bag_info(path)
    assert result.returncode == 2
    assert result.stdout == "" and len(result.stderr.strip().splitlines()) == 1
    assert message in result.stderr and str(path) in result.stderr


def test_corrupt_chunk_is_skipped_and_named(finished, tmp_path: Path) -> None:
    path, written = finished
    from mcap.reader import make_reader

    with open(path, "rb") as stream:
        victim = make_reader(stream).get_summary().chunk_indexes[2]
    data = bytearray(path.read_bytes())
    middle = victim.chunk_start_offset + victim.chunk_length // 2
    data[middle : middle + 16] = bytes(16)
    broken = tmp_path / "corrupt.mcap"
    broken.write_bytes(bytes(data))
    bag = load_bag(broken)
    report = bag.reports[0]
    assert (
        report.complete
        and report.skipped
        and f"chunk at byte {victim.chunk_start_offset}" in report.skipped[0]
    )
    assert 0 < sum(len(d) for d in bag.topics.values()) < 400 * 6


def test_unknown_schema_is_skipped_with_a_warning_naming_the_topic(tmp_path: Path) -> None:
    from hems_msgs.msg import WireForce
    from mcap.writer import Writer
    from rclpy.serialization import serialize_message

    from hems_ros.codec.msgdefs import full_definition

    path = tmp_path / "mixed.mcap"
    with open(path, "wb") as stream:
        writer = Writer(stream)
        writer.start("ros2", "test")
        good = writer.register_schema(
            "hems_msgs/msg/WireForce",
            "ros2msg",
            full_definition("hems_msgs/msg/WireForce").encode(),
        )
        proto = writer.register_schema("acme.Reading", "protobuf", b"\x0a\x00")
        partial = writer.register_schema(
            "acme_msgs/msg/Thing", "ros2msg", b"acme_msgs/Missing inner\n"
        )
        channels = {
            writer.register_channel("/hems/index/wire_force", "cdr", good): True,
            writer.register_channel("/acme/proto", "protobuf", proto): False,
            writer.register_channel("/acme/thing", "cdr", partial): False,
        }
        for i in range(10):
            for channel in channels:
                writer.add_message(channel, i, serialize_message(WireForce(force=float(i))), i)
        writer.finish()
    with pytest.warns(BagWarning) as caught:
        bag = load_bag(path)
    texts = [str(w.message) for w in caught]
    assert any("/acme/proto" in t and "protobuf" in t for t in texts)
    assert any("/acme/thing" in t and "acme_msgs/msg/Missing" in t for t in texts)
    assert set(bag.topics) == {"/hems/index/wire_force"} and list(
        bag["/hems/index/wire_force"]["force"]
    ) == list(range(10))
    result = hems_bag_info(path)
    assert (
        result.returncode == 0
        and "warning: skipping topic /acme/proto: unknown schema" in result.stdout
    )
