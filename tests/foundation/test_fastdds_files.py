"""Orphaned Fast DDS shared-memory files are removed, a live process's files are not: on
files laid out as Fast DDS names them, and on a real participant alive and then killed."""

from __future__ import annotations

import fcntl
import mmap
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from hems_ros.fastdds_files import SHM_DIR, remove_orphans
from hems_ros.rosenv import child_environment

SEGMENT = "fastdds_0123456789abcdef"
PORT = "fastdds_port7415"


def _files(folder: Path, *names: str, age_s: float = 60.0) -> None:
    for name in names:
        path = folder / name
        path.write_bytes(b"")
        os.utime(path, (time.time() - age_s, time.time() - age_s))


def test_a_segment_and_a_port_no_process_holds_go_with_the_port_mutex(tmp_path):
    _files(tmp_path, SEGMENT, SEGMENT + "_el", PORT, PORT + "_el", f"sem.{PORT}_mutex")
    _files(tmp_path, "lttng-ust-wait-6", "fastdds_notours", "sem.other")
    assert remove_orphans(tmp_path) == 5
    assert sorted(os.listdir(tmp_path)) == ["fastdds_notours", "lttng-ust-wait-6", "sem.other"]


def test_files_a_live_process_holds_stay(tmp_path):
    _files(tmp_path, SEGMENT, SEGMENT + "_el", PORT, PORT + "_el", PORT + "_sl")
    with (
        (tmp_path / SEGMENT).with_name(SEGMENT + "_el").open("rb") as segment_lock,
        (tmp_path / (PORT + "_sl")).open("rb") as shared_reader,
    ):
        fcntl.flock(segment_lock, fcntl.LOCK_EX)
        fcntl.flock(shared_reader, fcntl.LOCK_SH)  # one reader alive: the whole port stays
        assert remove_orphans(tmp_path) == 0
    assert remove_orphans(tmp_path) == 5
    assert os.listdir(tmp_path) == []


def test_young_lock_files_stay_as_a_starting_process_may_not_hold_them_yet(tmp_path):
    _files(tmp_path, SEGMENT, SEGMENT + "_el", age_s=1.0)
    assert remove_orphans(tmp_path) == 0
    assert remove_orphans(tmp_path, min_age_s=0.5) == 2


def test_a_port_without_lock_files_goes_unless_a_live_process_maps_it(tmp_path):
    """A writer killed after the port's owner had gone leaves the port with no lock file; the
    next owner of its number would reuse it with its first creator's settings."""
    left, in_use = "fastdds_port7417", "fastdds_port7419"
    (tmp_path / in_use).write_bytes(bytes(4096))
    _files(tmp_path, left, f"sem.{left}_mutex", f"sem.{in_use}_mutex")
    os.utime(tmp_path / in_use, (time.time() - 60.0, time.time() - 60.0))
    with (tmp_path / in_use).open("r+b") as f, mmap.mmap(f.fileno(), 4096):
        assert remove_orphans(tmp_path) == 2
        assert sorted(os.listdir(tmp_path)) == [in_use, f"sem.{in_use}_mutex"]
    assert remove_orphans(tmp_path, min_age_s=0.0) == 2
    assert os.listdir(tmp_path) == []


def test_no_shared_memory_folder_is_nothing_to_do(tmp_path):
    assert remove_orphans(tmp_path / "absent") == 0


PARTICIPANT = """
import sys, time, rclpy
rclpy.init()
node = rclpy.create_node("orphan_test")
node.create_publisher(__import__("std_msgs.msg").msg.Int32, "orphan_test", 10)
print("up", flush=True)
time.sleep(60)
"""


def _ours(before: set[str]) -> set[str]:
    return {n for n in set(os.listdir(SHM_DIR)) - before if n.startswith(("fastdds", "sem.fast"))}


def test_a_live_participants_files_stay_and_a_killed_ones_go():
    before = set(os.listdir(SHM_DIR))
    process = subprocess.Popen(
        [sys.executable, "-c", PARTICIPANT],
        env=child_environment(),
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout is not None and process.stdout.readline().strip() == "up"
        made = _ours(before)
        assert any(n.endswith("_el") for n in made), made
        remove_orphans(min_age_s=0.0)
        assert made <= set(os.listdir(SHM_DIR)), made - set(os.listdir(SHM_DIR))
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    assert made <= set(os.listdir(SHM_DIR))  # a killed process leaves them
    remove_orphans(min_age_s=0.0)
    locked = {n[:-3] for n in made if n.endswith(("_el", "_sl"))}
    left = made & set(os.listdir(SHM_DIR))
    assert not {n for n in left if n in locked or n[:-3] in locked}, left
