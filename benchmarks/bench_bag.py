"""Bag speed benchmark: write and read the node graph's message mix.

The mix follows the graph per finger: EncoderReading and WireForce (sensor streams),
ActuatorState (simulation truth), DutyCommand (controller output), plus one JointState for
the hand; six fingers. Messages are serialized once with rclpy and written as bytes, as the
recorder does, so the write rate is that of ``BagWriter.write`` (chunking and zstd included).
Read = ``load_bag``: scan, decompress and decode every message into numpy columns.

Floors: write >= 50,000 msg/s, read >= 200,000 msg/s. Prints measured rates and ratios.
Run: python benchmarks/bench_bag.py [--messages N] [--smoke]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import smoke

from hems_ros.bag import BagWriter, bag_info, load_bag, offered_qos

WRITE_FLOOR = 50_000
READ_FLOOR = 200_000
FINGERS = ("thumb_flexion", "thumb_abduction", "index", "middle", "ring", "little")


def message_mix(count: int) -> list[tuple[str, str, bytes]]:
    """``count`` serialized messages cycling through the graph's topics, values varying."""
    from hems_msgs.msg import ActuatorState, DutyCommand, EncoderReading, WireForce
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import JointState

    topics = []
    for finger in FINGERS:
        topics += [
            (f"/hems/{finger}/encoder", "hems_msgs/msg/EncoderReading"),
            (f"/hems/{finger}/wire_force", "hems_msgs/msg/WireForce"),
            (f"/hems/sim/{finger}/state", "hems_msgs/msg/ActuatorState"),
            (f"/hems/{finger}/duty", "hems_msgs/msg/DutyCommand"),
        ]
    topics.append(("/hems/joint_states", "sensor_msgs/msg/JointState"))
    out = []
    for i in range(count):
        topic, type_name = topics[i % len(topics)]
        finger = topic.split("/")[-2]
        if type_name.endswith("EncoderReading"):
            msg = EncoderReading(
                finger=finger, counts=i, position=i * 1e-5, resolution=1e-5, sequence=i
            )
        elif type_name.endswith("WireForce"):
            msg = WireForce(finger=finger, force=0.01 * i, sequence=i)
        elif type_name.endswith("ActuatorState"):
            msg = ActuatorState(
                finger=finger,
                wire_temperature_c=25.0 + i % 50,
                stress=1e6 * (i % 7),
                wire_force=0.1 * (i % 100),
                sequence=i,
            )
        elif type_name.endswith("DutyCommand"):
            msg = DutyCommand(finger=finger, duty_percent=float(i % 100), sequence=i)
        else:
            msg = JointState(name=list(FINGERS), position=[0.001 * i] * 6, velocity=[0.0] * 6)
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(i * 1_000_000, 1_000_000_000)
        out.append((topic, type_name, serialize_message(msg)))
    return out


def bench(count: int) -> dict[str, float]:
    mix = message_mix(count)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "bench"
        start = time.perf_counter()
        with BagWriter(folder) as writer:
            channels = {}
            for topic, type_name, _ in mix[:200]:
                if topic not in channels:
                    channels[topic] = writer.add_topic(
                        topic, type_name, [offered_qos(False, False, 10)]
                    )
            write = writer.write
            for i, (topic, _, data) in enumerate(mix):
                write(channels[topic], 1_000_000_000 + i * 20_000, data)
        write_s = time.perf_counter() - start
        size = sum(f.stat().st_size for f in folder.iterdir())
        start = time.perf_counter()
        bag = load_bag(folder)
        read_s = time.perf_counter() - start
        start = time.perf_counter()
        info = bag_info(folder)
        info_s = time.perf_counter() - start
    decoded = sum(len(t) for t in bag.topics.values())
    if decoded != count or info.message_count != count:
        raise SystemExit(f"read back {decoded} (info {info.message_count}) of {count} messages")
    return {
        "write": count / write_s,
        "read": count / read_s,
        "info": count / info_s,
        "bytes_per_message": size / count,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=int, default=200_000)
    args = smoke.parse_args(parser, messages=5_000)
    result = bench(args.messages)
    print(
        f"bag benchmark: {args.messages} messages, graph mix, zstd chunks, "
        f"{result['bytes_per_message']:.1f} bytes/message on disk"
    )
    print(
        f"  write {result['write']:>10,.0f} msg/s   floor {WRITE_FLOOR:,}   ratio "
        f"{result['write'] / WRITE_FLOOR:.2f}"
    )
    print(
        f"  read  {result['read']:>10,.0f} msg/s   floor {READ_FLOOR:,}  ratio "
        f"{result['read'] / READ_FLOOR:.2f}   (decoded into numpy columns)"
    )
    print(f"  info  {result['info']:>10,.0f} msg/s   (scan and count, no decode)")
    return 0 if args.smoke or result["write"] >= WRITE_FLOOR and result["read"] >= READ_FLOOR else 1


if __name__ == "__main__":
    raise SystemExit(main())
