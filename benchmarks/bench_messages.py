"""Per-message CPU of typed and serialized messages between two processes.

The graph's nodes publish and take their hot topics serialized (hems_ros/ros/wire.py)
instead of as rclpy message objects. This benchmark measures both ways side by side on the
graph's busiest message, EncoderReading, over the graph's sensor QoS: a subscriber process
(lean_spin, as in the nodes) takes ``--count`` messages while this process publishes them
at 1 kHz, and each side reports its CPU per message. Typed: build the message and publish
it; take it as a message object and read its fields. Serialized: encode the named tuple and
publish the bytes; take the bytes and decode them.

Usage: .venv/bin/python benchmarks/bench_messages.py [--count 5000] [--smoke]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import smoke

from hems_ros.rosenv import apply_network_defaults, use_private_domain

apply_network_defaults()
DOMAIN_LOCK = use_private_domain()  # no test run or other benchmark shares it

TOPIC = "/hems_bench/encoder"


def subscriber(serialized: bool, count: int) -> None:
    """Child process: take ``count`` messages (or give up after 60 s) and print CPU per message."""
    import rclpy
    from hems_msgs.msg import EncoderReading

    from hems_ros.ros import lean_spin, qos
    from hems_ros.ros.wire import codec

    rclpy.init()
    node = rclpy.create_node("bench_messages_subscriber")
    encoder = codec(EncoderReading)
    seen = []

    def on_message(message) -> None:
        if serialized:
            message = encoder.decode(message)
            seen.append(message.position + message.header_stamp_sec)
        else:
            seen.append(message.position + message.header.stamp.sec)

    subscription = node.create_subscription(
        EncoderReading, TOPIC, on_message, qos.SENSOR, raw=serialized
    )
    print("ready", flush=True)
    deadline = time.monotonic() + 60.0
    cpu0 = time.process_time()
    lean_spin.loop(
        node.context,
        lambda: ([subscription], [], []),
        keep_going=lambda: len(seen) < count and time.monotonic() < deadline,
    )
    cpu_us = 1e6 * (time.process_time() - cpu0) / max(len(seen), 1)
    print(json.dumps({"taken": len(seen), "cpu_us": cpu_us}), flush=True)
    node.destroy_node()
    rclpy.shutdown()


def publish(serialized: bool, count: int) -> dict:
    import rclpy
    from hems_msgs.msg import EncoderReading

    from hems_ros.ros import qos
    from hems_ros.ros.wire import codec

    child = subprocess.Popen(
        [
            sys.executable,
            __file__,
            "--subscriber",
            "serialized" if serialized else "typed",
            "--count",
            str(count),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert child.stdout is not None  # stdout=PIPE
    try:
        assert child.stdout.readline().strip() == "ready"
        rclpy.init()
        node = rclpy.create_node("bench_messages_publisher")
        publisher = node.create_publisher(EncoderReading, TOPIC, qos.SENSOR)
        deadline = time.monotonic() + 30
        while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.5)
        encoder = codec(EncoderReading)
        spent = 0.0
        for k in range(count):
            t0 = time.thread_time()
            if serialized:
                publisher.publish(
                    encoder.encode(
                        encoder.fields(
                            header_stamp_sec=k,
                            header_stamp_nanosec=k,
                            header_frame_id="",
                            finger="index",
                            counts=k,
                            position=k * 1e-6,
                            resolution=1e-6,
                            duty_percent=0.0,
                            on_current=float("nan"),
                            on_voltage=float("nan"),
                            sequence=k,
                        )
                    )
                )
            else:
                message = EncoderReading(
                    finger="index", counts=k, position=k * 1e-6, resolution=1e-6, sequence=k
                )
                message.header.stamp.sec, message.header.stamp.nanosec = k, k
                publisher.publish(message)
            spent += time.thread_time() - t0
            time.sleep(0.001)  # 1 kHz: the subscriber keeps up, so nothing is lost in its queue
        received = json.loads(child.communicate(timeout=90)[0].splitlines()[-1])
        node.destroy_node()
        rclpy.shutdown()
    finally:
        if child.poll() is None:
            child.kill()
    return {
        "publish_us": 1e6 * spent / count,
        "take_us": received["cpu_us"],
        "taken": received["taken"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=5000, help="messages per variant")
    parser.add_argument("--subscriber", choices=("typed", "serialized"), help=argparse.SUPPRESS)
    args = smoke.parse_args(parser, count=200)
    if args.subscriber:
        subscriber(args.subscriber == "serialized", args.count)
        return
    print(
        f"EncoderReading between two processes, {args.count} messages per variant at 1 kHz, "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    results = {name: publish(name == "serialized", args.count) for name in ("typed", "serialized")}
    print(f"{'variant':<11} {'publish us':>11} {'take us':>9} {'taken':>7}")
    for name, r in results.items():
        print(f"{name:<11} {r['publish_us']:>11.1f} {r['take_us']:>9.1f} {r['taken']:>7}")
    typed, raw = results["typed"], results["serialized"]
    print(
        f"typed / serialized: publish {typed['publish_us'] / raw['publish_us']:.2f}x, "
        f"take {typed['take_us'] / raw['take_us']:.2f}x"
    )


if __name__ == "__main__":
    main()
