"""The recorder node in its own process recording synthetic publishers in another (real DDS)."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from bag_helpers import COMMAND_SCRIPT, PUBLISHER_SCRIPT, run_command_publisher
from synthetic_publisher import STATUS_TOPIC, STREAMS, expected_values

from hems_ros.bag import load_bag
from hems_ros.bag.recording import RecorderProcess, record_for
from hems_ros.processes import stop_process
from hems_ros.rosenv import child_environment

TOPICS = list(STREAMS) + [STATUS_TOPIC]


def publish(count: int, rate: float, linger: float = 1.0) -> subprocess.Popen:
    return subprocess.Popen(
        [
            sys.executable,
            str(PUBLISHER_SCRIPT),
            "--count",
            str(count),
            "--rate",
            str(rate),
            "--linger",
            str(linger),
        ],
        env=child_environment(),
        stdout=subprocess.PIPE,
        text=True,
    )


def published_counts(publisher: subprocess.Popen) -> dict[str, int]:
    out, _ = publisher.communicate(timeout=60)
    assert publisher.returncode == 0, out
    return json.loads(out.strip().splitlines()[-1])["published"]


def check_streams(bag, counts: dict[str, int]) -> None:
    for topic, count in counts.items():
        data = bag[topic]
        assert len(data) == count, topic
        if topic in STREAMS and "sequence" in data.fields:
            assert np.array_equal(data["sequence"], np.arange(count)), topic
        if topic in STREAMS:
            for name, value in expected_values(topic, count - 1).items():
                assert data[name][-1] == value, (topic, name)
    assert np.all(np.diff(bag["/hems/test/duty"].log_time_ns) >= 0)


def test_records_every_message_and_finishes_on_sigterm(ros_domain_id: int, tmp_path: Path) -> None:
    output = tmp_path / "graph"
    recorder = RecorderProcess(output, regex=r"/hems/.*", flush_period=0.2)
    try:
        publisher = publish(count=2000, rate=1000.0)
        recorder.wait_for_topics(TOPICS)
        recorder.wait_for_messages(STREAMS, timeout=20.0)
        counts = published_counts(publisher)
    finally:
        info = recorder.stop()
    # each topic's first message is announced once, as a run's tool waits for it
    assert recorder.heard == set(counts)
    assert sum("first message on" in line for line in recorder.log) == len(counts)
    assert recorder.process.returncode in (0, -15)
    assert any("bag finished" in line for line in recorder.log)
    assert (output / "metadata.yaml").is_file()
    assert info.reports[0].complete and {t: e.count for t, e in info.topics.items()} == counts
    bag = load_bag(output)
    check_streams(bag, counts)
    assert (
        bag["/hems/supervisor/status"]["state_name"][0] == "ENABLED"
    )  # latched, published before we joined

    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader

    with open(output / "graph_0.mcap", "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary.statistics.message_count == sum(counts.values())
    with AnyReader([output]) as reader:
        duty = [c for c in reader.connections if c.topic == "/hems/test/duty"]
        values = [
            reader.deserialize(raw, c.msgtype).duty_percent
            for c, _, raw in reader.messages(connections=duty)
        ]
    assert values == [
        expected_values("/hems/test/duty", i)["duty_percent"]
        for i in range(counts["/hems/test/duty"])
    ]


def test_sigkill_keeps_every_flushed_chunk(ros_domain_id: int, tmp_path: Path) -> None:
    output = tmp_path / "killed"
    recorder = RecorderProcess(output, topics=list(STREAMS), flush_period=0.2)
    try:
        publisher = publish(count=1500, rate=1000.0)
        recorder.wait_for_topics(STREAMS)
        counts = published_counts(publisher)
        time.sleep(0.6)  # > flush_period: the last messages are in a finished chunk now
    finally:
        recorder.kill()
    assert recorder.process.returncode == -9
    assert not (output / "metadata.yaml").exists()
    bag = load_bag(output)
    report = bag.reports[0]
    assert not report.complete and report.chunks >= 5 and "did not finish" in report.reason
    check_streams(bag, {t: c for t, c in counts.items() if t in STREAMS})


def test_record_for_a_fixed_time(ros_domain_id: int, tmp_path: Path) -> None:
    publisher = publish(count=1500, rate=500.0, linger=0.2)
    try:
        started = time.monotonic()
        info = record_for(tmp_path / "timed", 2.0, regex=r"/hems/test/.*|/hems/joint_states")
        elapsed = time.monotonic() - started
    finally:
        publisher.kill()
        publisher.wait()
    assert 2.0 <= elapsed < 15.0
    assert info.reports[0].complete and set(info.topics) == set(STREAMS)
    assert info.topics["/hems/test/encoder"].count > 100


def test_recorder_rejects_a_used_folder(tmp_path: Path) -> None:
    (tmp_path / "used").mkdir()
    (tmp_path / "used" / "file").write_text("x")
    recorder = RecorderProcess(tmp_path / "used")
    with pytest.raises(RuntimeError, match="code 2"):
        recorder.wait(timeout=30)


def test_recorder_names_a_folder_it_cannot_make(tmp_path: Path) -> None:
    # was a traceback (FileNotFoundError / NotADirectoryError escaped the configuration check)
    (tmp_path / "a_file").write_text("x")
    recorder = RecorderProcess(tmp_path / "a_file" / "bag")
    with pytest.raises(RuntimeError, match="code 2") as info:
        recorder.wait(timeout=30)
    assert (
        f"Recorder: invalid configuration: [Errno 20] Not a directory: "
        f"'{tmp_path / 'a_file' / 'bag'}'" in str(info.value)
    )
    assert "Traceback" not in "\n".join(recorder.log)


def test_stop_twice_gives_the_same_bag_and_an_error_leaving_the_block_stays_the_error(
    ros_domain_id: int, tmp_path: Path
) -> None:
    publisher = publish(count=1500, rate=500.0)
    try:
        with RecorderProcess(tmp_path / "twice", topics=list(STREAMS)) as recorder:
            recorder.wait_for_topics(STREAMS)
            info = recorder.stop()
        assert recorder.stop() is info and info.reports[0].complete

        # a recorder that died under way fails its stop; leaving the block on another error,
        # the other error is what the caller sees, with the recorder's failure as a note
        with pytest.raises(KeyError) as raised:
            with RecorderProcess(tmp_path / "crashed", topics=list(STREAMS)) as recorder:
                recorder.wait_for_topics(STREAMS)
                recorder.process.kill()
                raise KeyError("the scenario's own error")
    finally:
        publisher.kill()
        publisher.wait()
    assert recorder.process.returncode == -9
    assert any(
        "stopping the recorder failed" in note and "killed by SIGKILL" in note
        for note in raised.value.__notes__
    )


@pytest.fixture
def listener(ros_domain_id: int):
    """A subscription to /hems/index/setpoint, as a controller has: the topic is in the graph
    before any publisher."""
    import rclpy
    from hems_msgs.msg import FingerSetpoint
    from rclpy.context import Context

    from hems_ros.ros import qos

    context = Context()
    rclpy.init(context=context)
    node = rclpy.create_node("controller_stand_in", context=context)
    node.create_subscription(FingerSetpoint, "/hems/index/setpoint", lambda m: None, qos.COMMAND)
    yield node
    node.destroy_node()
    rclpy.shutdown(context=context)


def offered_reliability(folder: Path, topic: str) -> list[str]:
    import yaml

    meta = yaml.safe_load((folder / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    entry = next(
        t["topic_metadata"]
        for t in meta["topics_with_message_count"]
        if t["topic_metadata"]["name"] == topic
    )
    return [q["reliability"] for q in entry["offered_qos_profiles"]]


def record_commands(output: Path, *args: str) -> tuple[RecorderProcess, object]:
    """Record /hems/index/setpoint (a listener keeps it in the graph) while one command_publisher
    process with ``args`` runs; the recorder and its bag summary."""
    recorder = RecorderProcess(output, topics=["/hems/index/setpoint"], discovery_period=0.05)
    try:
        recorder.wait_for_topics(["/hems/index/setpoint"])  # no publisher in the graph yet
        # the error also quotes how the recorder subscribed to the silent topic
        with pytest.raises(
            TimeoutError,
            match=r"no message of \['/hems/index/setpoint'\].* \| .*recording /hems/index/setpoint "
            r"\[hems_msgs/msg/FingerSetpoint\] reliable, volatile, before any publisher$",
        ):
            recorder.wait_for_messages(["/hems/index/setpoint"], timeout=0.3)
        run_command_publisher(*args)
    finally:
        info = recorder.stop()
    return recorder, info


def recorded_values(output: Path) -> list[float]:
    return list(load_bag(output)["/hems/index/setpoint"]["value"])


def test_a_topic_without_publishers_is_subscribed_at_once_so_one_shot_commands_are_recorded(
    listener, tmp_path: Path
) -> None:
    """`hems setpoint` and `ros2 topic pub --once` publish as soon as their writer has matched:
    a recorder that subscribed only once it saw that writer would have matched it after the
    sample was sent, and a volatile reader never gets a sample written before it matched.
    (The writer here stays until its heartbeat, 3 s, could repair a sample the recorder's
    reader dropped because its own side of the match came later.)"""
    # the listener and the recorder matched, then three samples at once
    recorder, info = record_commands(
        tmp_path / "commands",
        "--value",
        "5",
        "--count",
        "3",
        "--subscribers",
        "2",
        "--linger",
        "3.5",
    )
    assert any("before any publisher" in line for line in recorder.log)
    assert info.topics["/hems/index/setpoint"].count == 3
    assert recorded_values(tmp_path / "commands") == pytest.approx([0.005, 0.006, 0.007], abs=1e-12)
    # the bag names the publishers' QoS (rosbag2 metadata), learnt when they appeared
    assert offered_reliability(tmp_path / "commands", "/hems/index/setpoint") == ["reliable"]


def test_a_waiting_subscription_turns_best_effort_for_a_best_effort_publisher(
    listener, tmp_path: Path
) -> None:
    # a reliable reader never matches a best-effort writer (the listener never does): the
    # publisher waits for the recorder's new best-effort subscription
    _, info = record_commands(
        tmp_path / "late_best_effort",
        "--best-effort",
        "--subscribers",
        "1",
        "--count",
        "20",
        "--value",
        "1",
    )
    assert info.topics["/hems/index/setpoint"].count == 20
    assert recorded_values(tmp_path / "late_best_effort") == pytest.approx(
        [(1 + k) * 1e-3 for k in range(20)], abs=1e-12
    )
    assert offered_reliability(tmp_path / "late_best_effort", "/hems/index/setpoint") == [
        "best_effort"
    ]


def test_a_waiting_subscription_takes_a_latched_sample_sent_before_it_matched(
    listener, tmp_path: Path
) -> None:
    output = tmp_path / "late_latched"
    recorder = RecorderProcess(output, topics=["/hems/index/setpoint"], discovery_period=0.05)
    publisher = None
    try:
        recorder.wait_for_topics(["/hems/index/setpoint"])
        # published at once, before anything can have matched; the writer keeps it for late
        # transient-local readers and stays until the recorder has one (discovery between
        # processes now and then takes seconds, so no fixed wait)
        publisher = subprocess.Popen(
            [
                sys.executable,
                str(COMMAND_SCRIPT),
                "--latched",
                "--subscribers",
                "0",
                "--value",
                "7",
                "--linger",
                "60",
            ],
            env=child_environment(),
        )
        deadline = time.monotonic() + 30.0
        while not any(
            "/hems/index/setpoint" in line and "transient_local" in line for line in recorder.log
        ):
            assert time.monotonic() < deadline, "the recorder never subscribed transient local"
            time.sleep(0.05)
        time.sleep(2.0)  # the writer's history reaches the new reader once they have matched
    finally:
        if publisher is not None:
            stop_process(publisher, 10.0)
        info = recorder.stop()
    assert info.topics["/hems/index/setpoint"].count == 1
    assert recorded_values(output) == pytest.approx([0.007], abs=1e-12)


def test_a_recorder_stopped_while_it_subscribes_still_finishes_its_bag(
    ros_domain_id: int, tmp_path: Path
) -> None:
    # SIGTERM right after the first topic was reported subscribed: the recorder was still
    # subscribing in its constructor, whose next rcl call failed on the shut-down context, and
    # the bag was left at its 41-byte header (once in a full `make test` on a busy host).
    # The publisher outlasts five recorder start-ups on a slow host; it is killed at the end.
    publisher = publish(count=60_000, rate=500.0)
    try:
        for attempt in range(5):
            recorder = RecorderProcess(tmp_path / f"early_{attempt}", topics=TOPICS)
            recorder.wait_for_topics(TOPICS[:1])
            info = recorder.stop()
            assert info.reports[0].complete, (attempt, info.reports[0].reason, recorder.log[-5:])
    finally:
        publisher.kill()
        publisher.wait()


def test_a_recorder_ends_with_the_process_that_started_it(
    ros_domain_id: int, tmp_path: Path
) -> None:
    # `hems step` died once in a Fast DDS fault; its recorder went on recording in the test
    # domain and the next tests met its readers. It now gets SIGTERM with its parent's death and
    # finishes the bag.
    import os
    import signal

    from hems_ros.bag import bag_info

    output = tmp_path / "orphan"
    script = (
        "import sys, time\nfrom pathlib import Path\nfrom hems_ros.bag.recording import "
        f"RecorderProcess\nr = RecorderProcess(Path({str(output)!r}), topics={TOPICS!r})\n"
        f"r.wait_for_topics({TOPICS[:1]!r})\nprint(r.process.pid, flush=True)\ntime.sleep(120)\n"
    )
    publisher = publish(count=60_000, rate=500.0)  # outlasts any start-up; killed at the end
    parent = subprocess.Popen(
        [sys.executable, "-c", script], env=child_environment(), stdout=subprocess.PIPE, text=True
    )
    recorder_pid = None
    try:
        recorder_pid = int(parent.stdout.readline())
        parent.send_signal(signal.SIGKILL)
        parent.wait(timeout=10)
        deadline = time.monotonic() + 15
        while os.path.exists(f"/proc/{recorder_pid}") and time.monotonic() < deadline:
            with open(f"/proc/{recorder_pid}/stat") as stat:
                if stat.read().rsplit(") ", 1)[1].startswith("Z"):
                    break  # exited; its parent is gone, so nobody has reaped it yet
            time.sleep(0.1)
        assert time.monotonic() < deadline, "the recorder outlived its parent"
    finally:
        publisher.kill()
        publisher.wait()
        if parent.poll() is None:
            parent.kill()
        if recorder_pid is not None and os.path.exists(f"/proc/{recorder_pid}"):
            os.kill(recorder_pid, signal.SIGKILL)  # outlived its parent: not left in the domain
    assert bag_info(output).reports[0].complete
