"""``hems replay`` in its own process republishes a bag with its timing, remapping and /clock."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from rclpy.serialization import serialize_message

from hems_ros.bag import BagWriter, offered_qos
from hems_ros.cli.replay import parse_remaps
from hems_ros.rosenv import child_environment

START_NS = 5_000_000_000
STEP_NS = 100_000_000  # 10 Hz in the bag


def make_bag(folder: Path, count: int = 11) -> None:
    from hems_msgs.msg import DutyCommand, SupervisorStatus

    with BagWriter(folder) as writer:
        duty = writer.add_topic(
            "/hems/index/duty", "hems_msgs/msg/DutyCommand", [offered_qos(True, False, 1)]
        )
        status = writer.add_topic(
            "/hems/supervisor/status",
            "hems_msgs/msg/SupervisorStatus",
            [offered_qos(True, True, 1)],
        )
        writer.write(
            status, START_NS, serialize_message(SupervisorStatus(state=1, state_name="ENABLED"))
        )
        for i in range(count):
            writer.write(
                duty,
                START_NS + i * STEP_NS,
                serialize_message(DutyCommand(duty_percent=2.5 * i, sequence=i)),
            )


@pytest.mark.parametrize("rate", [1.0, 2.0])
def test_replay_keeps_timing_remaps_and_publishes_clock(
    ros_domain_id: int, tmp_path: Path, rate: float
) -> None:
    import rclpy
    from hems_msgs.msg import DutyCommand, SupervisorStatus
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from rosgraph_msgs.msg import Clock

    make_bag(tmp_path / "bag")
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("replay_listener", context=context)
    arrivals: list[tuple[float, DutyCommand]] = []
    clocks: list[int] = []
    statuses: list[str] = []
    node.create_subscription(
        DutyCommand, "/replayed/duty", lambda m: arrivals.append((time.monotonic(), m)), 100
    )
    node.create_subscription(
        Clock, "/clock", lambda m: clocks.append(m.clock.sec * 10**9 + m.clock.nanosec), 100
    )
    node.create_subscription(
        SupervisorStatus,
        "/hems/supervisor/status",
        lambda m: statuses.append(m.state_name),
        QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        ),
    )
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    replay = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "hems_ros.cli.main",
            "replay",
            str(tmp_path / "bag"),
            "--rate",
            str(rate),
            "--remap",
            "/hems/index/duty:=/replayed/duty",
            "--clock",
            "50",
            "--start-delay",
            "0.5",
            "--wait-subscribers",
            "20",
        ],
        env=child_environment(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 30
        while replay.poll() is None and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.01)
        end = time.monotonic() + 0.5
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.01)
        out, err = replay.communicate(timeout=10)
    finally:
        if replay.poll() is None:
            replay.kill()
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    assert replay.returncode == 0, err
    assert "replayed 12 messages on 2 topics" in out
    assert [m.sequence for _, m in arrivals] == list(range(11))
    assert [m.duty_percent for _, m in arrivals] == [2.5 * i for i in range(11)]
    gaps = np.diff([t for t, _ in arrivals])
    assert np.allclose(gaps, STEP_NS * 1e-9 / rate, atol=0.03), gaps
    assert (arrivals[-1][0] - arrivals[0][0]) == pytest.approx(1.0 / rate, abs=0.05)
    assert statuses == ["ENABLED"]
    assert len(clocks) >= 10 and np.all(np.diff(clocks) >= 0)
    assert START_NS <= clocks[0] and clocks[-1] == START_NS + 10 * STEP_NS


def test_remap_syntax() -> None:
    assert parse_remaps(["/a:=/b"]) == {"/a": "/b"}
    with pytest.raises(ValueError, match="form /from:=/to"):
        parse_remaps(["/a=/b"])


def test_replay_offers_the_recorded_liveliness_lease() -> None:
    """A reader asking for a lease (the units and controllers of the supervisor's status)
    matches only a writer that offers one at most as long."""
    import yaml

    from hems_ros.cli.replay import replay_qos

    def lease_ns(*profiles: dict) -> int:
        return replay_qos(yaml.safe_dump(list(profiles))).liveliness_lease_duration.nanoseconds

    leased = offered_qos(True, True, 1, 30_000_000)
    assert lease_ns(leased) == 30_000_000
    assert lease_ns(leased, offered_qos(True, True, 1, 5_000_000)) == 5_000_000
    assert lease_ns(leased, offered_qos(True, True, 1)) == 0  # one publisher offered none
    assert lease_ns(offered_qos()) == 0
    assert replay_qos("").liveliness_lease_duration.nanoseconds == 0


@pytest.mark.parametrize("signal_name", ["SIGTERM", "SIGINT"])
def test_a_signal_stops_replay_cleanly(
    ros_domain_id: int, tmp_path: Path, signal_name: str
) -> None:
    # a replay waiting for acknowledgements on a context the signal has shut down must not end
    # in a traceback
    import signal

    make_bag(tmp_path / "bag", count=101)  # 10 s at 10 Hz
    replay = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "hems_ros.cli.main",
            "replay",
            str(tmp_path / "bag"),
            "--loop",
            "--start-delay",
            "0",
        ],
        env=child_environment(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        time.sleep(3.0)
        replay.send_signal(getattr(signal, signal_name))
        out, err = replay.communicate(timeout=20)
    finally:
        if replay.poll() is None:
            replay.kill()
    assert replay.returncode == 0, err
    assert "Traceback" not in err
    assert "(0 full passes; stopped by a signal)" in out
    published = int(out.split("replayed ")[1].split(" messages")[0])
    assert 2 <= published <= 40
