"""A long recording closes thousands of chunks; the writer keeps each chunk's index as the
bytes it will write (hems_ros.bag.writer._WrittenRecord), and the finished file still reads
per topic through its chunk and message indexes (rosbags) and whole (our reader)."""

from __future__ import annotations

from rosbags.rosbag2 import Reader

from hems_ros.bag import load_bag
from hems_ros.bag.writer import BagWriter, _WrittenRecord

STRING = b"\x00\x01\x00\x00" + b"\x05\x00\x00\x00abcd\x00"


def test_chunk_indexes_are_kept_written_and_the_bag_reads_per_topic(tmp_path):
    writer = BagWriter(tmp_path / "bag")
    channels = [writer.add_topic(f"/t{i}", "std_msgs/msg/String") for i in range(40)]
    stamp = 0
    for _ in range(50):
        for channel in channels:
            for _ in range(3):
                writer.write(channel, stamp, STRING)
                stamp += 1
        writer.flush()
    assert len(writer._chunk_indexes) == 50
    assert all(
        isinstance(index, _WrittenRecord) and len(index.data) < 600
        for index in writer._chunk_indexes
    )
    writer.finish()
    bag = load_bag(tmp_path / "bag")
    assert bag.complete and sum(len(t) for t in bag.topics.values()) == 6000
    with Reader(tmp_path / "bag") as reader:
        wanted = [c for c in reader.connections if c.topic in ("/t0", "/t39")]
        stamps = [timestamp for _, timestamp, _ in reader.messages(connections=wanted)]
    assert len(stamps) == 300 and stamps == sorted(stamps)
    assert stamps[:3] == [0, 1, 2] and stamps[3:6] == [117, 118, 119]
