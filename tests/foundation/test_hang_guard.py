"""The hang guard fails a hung test and goes on; one that will not stop ends the run, named."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]
HUNG = """
import time

def test_sleeps():
    time.sleep(60)

def test_after_it():
    pass

def test_holds_the_interpreter():
    import ctypes
    libc = ctypes.PyDLL(None)  # its calls keep the GIL
    mutex = ctypes.create_string_buffer(64)  # a default pthread mutex is all zeros
    libc.pthread_mutex_lock(mutex)
    libc.pthread_mutex_lock(mutex)  # already this thread's: waits for ever, signals or not

def test_will_not_stop():
    while True:
        try:
            time.sleep(60)
        except BaseException:
            pass
"""


def _pytest(folder: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, HEMS_TEST_HANG_S="1", PYTHONPATH=str(TESTS))
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "hang_guard", "-p", "no:cacheprovider", *args],
        cwd=folder,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )


def test_a_hung_test_fails_and_the_run_goes_on(tmp_path: Path) -> None:
    (tmp_path / "test_hung.py").write_text(HUNG)
    result = _pytest(tmp_path, "-k", "sleeps or after_it", "test_hung.py")
    assert result.returncode == 1, result.stdout
    assert "still running after 1 s: stopped as hung" in result.stdout
    assert "1 failed, 1 passed" in result.stdout


def test_a_test_that_will_not_stop_ends_the_run_with_its_name_last(tmp_path: Path) -> None:
    (tmp_path / "test_hung.py").write_text(HUNG)
    result = _pytest(tmp_path, "test_hung.py::test_will_not_stop")
    assert result.returncode == 3
    assert "test_will_not_stop" in result.stderr.strip().splitlines()[-1]
    assert "Thread 0x" in result.stderr or "Current thread" in result.stderr


def test_a_call_that_holds_the_interpreter_is_stopped_with_every_stack(tmp_path: Path) -> None:
    (tmp_path / "test_hung.py").write_text(HUNG)
    result = _pytest(tmp_path, "test_hung.py::test_holds_the_interpreter")
    assert result.returncode != 0
    assert "Timeout (0:00:01" in result.stderr and "test_holds_the_interpreter" in result.stderr
