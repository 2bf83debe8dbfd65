"""Run the recorder node as a child process: ``record_for`` and ``RecorderProcess``.

For callers that start a graph and want it recorded (``hems up --record``, the demo, tests):

    with RecorderProcess("bags/run1", regex="/hems/.*") as recorder:
        recorder.wait_for_topics(["/hems/index/encoder"])
        ...                                  # run the scenario
    summary = recorder.result                # BagInfo of the finished bag

The child gets this process's environment with the project's network defaults. Stopping
sends SIGTERM (the recorder finishes the bag) and SIGKILL only if it does not exit in time.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterable
from pathlib import Path

from hems_ros.bag.reader import BagInfo, bag_info
from hems_ros.processes import exit_description, stop_process
from hems_ros.rosenv import RECORDER_PROFILES_FILE, child_environment, die_with_parent

READY_MARK = "]: recording "
FINISHED_MARK = "]: bag finished: "
HEARD_MARK = "]: first message on "


def recorder_command(
    output: str | os.PathLike,
    topics: Iterable[str] | None = None,
    regex: str | None = None,
    duration: float = 0.0,
    flush_period: float | None = None,
    chunk_size: int | None = None,
    compression: str | None = None,
    discovery_period: float | None = None,
) -> list[str]:
    """The command line of a recorder node with these parameters (values quoted as YAML)."""
    parameters: dict[str, object] = {"output": str(output), "duration": float(duration)}
    if topics:
        parameters["topics"] = list(topics)
    if regex:
        parameters["regex"] = regex
    optional = {
        "flush_period": flush_period,
        "chunk_size": chunk_size,
        "compression": compression,
        "discovery_period": discovery_period,
    }
    parameters.update({k: v for k, v in optional.items() if v is not None})
    command = [sys.executable, "-m", "hems_ros.nodes.recorder", "--ros-args"]
    for name, value in parameters.items():
        command += ["-p", f"{name}:={json.dumps(value)}"]
    return command


class RecorderProcess:
    """A recorder node in a child process, recording into ``output`` until ``stop``."""

    def __init__(
        self,
        output: str | os.PathLike,
        topics: Iterable[str] | None = None,
        regex: str | None = None,
        duration: float = 0.0,
        **options: object,
    ) -> None:
        self.output = Path(output)
        self.recording: list[str] = []
        self.heard: set[str] = set()  # topics of which a message reached the bag
        self.log: list[str] = []
        self.result: BagInfo | None = None
        self._changed = threading.Condition()
        env = child_environment(
            {"RCUTILS_LOGGING_BUFFERED_STREAM": "0", "PYTHONUNBUFFERED": "1"},
            RECORDER_PROFILES_FILE,
        )
        self.process = subprocess.Popen(
            recorder_command(self.output, topics, regex, duration, **options),  # type: ignore[arg-type]
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            preexec_fn=die_with_parent,
        )  # a crashed tool left its recorder recording on
        self._reader = threading.Thread(target=self._read_output, daemon=True)
        self._reader.start()

    def _read_output(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            with self._changed:
                self.log.append(line.rstrip("\n"))
                if READY_MARK in line:
                    self.recording.append(line.split(READY_MARK, 1)[1].split(" ", 1)[0])
                elif HEARD_MARK in line:
                    self.heard.add(line.split(HEARD_MARK, 1)[1].strip())
                self._changed.notify_all()
        with self._changed:
            self._changed.notify_all()

    def wait_for_topics(self, topics: Iterable[str], timeout: float = 20.0) -> None:
        """Block until the recorder has subscribed to every topic in ``topics``."""
        wanted = set(topics)
        self._wait_for(
            lambda: wanted - set(self.recording), "recorder did not subscribe to {}", timeout
        )

    def wait_for_messages(self, topics: Iterable[str], timeout: float = 20.0) -> None:
        """Block until a message of every topic in ``topics`` has reached the bag."""
        wanted = set(topics)
        self._wait_for(
            lambda: wanted - self.heard, "no message of {} reached the recorder", timeout
        )

    def _wait_for(self, missing, what: str, timeout: float) -> None:
        """Until ``missing()`` (read under the lock) is empty; TimeoutError naming them (``what``
        formatted with their sorted list) after ``timeout`` s, RuntimeError when the recorder
        exited."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while missing():
                if self.process.poll() is not None and not self._reader.is_alive():
                    raise RuntimeError(
                        f"recorder exited {exit_description(self.process.returncode)}: "
                        + " | ".join(self.log[-5:])
                    )
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise TimeoutError(
                        f"{what.format(sorted(missing()))} within {timeout:.0f} s"
                        + "".join(f" | {line}" for line in self._lines_on(missing()))
                    )
                self._changed.wait(min(remaining, 0.2))

    def _lines_on(self, topics: set[str]) -> list[str]:
        """The recorder's log lines on ``topics`` (how each was subscribed, say)."""
        return [line for line in self.log if any(f" {t} " in f"{line} " for t in topics)]

    def wait(self, timeout: float | None = None) -> BagInfo:
        """Wait for the recorder to exit by itself (``duration`` set); return the bag's info."""
        self.process.wait(timeout)
        return self._finish()

    def stop(self, timeout: float = 10.0) -> BagInfo:
        """SIGTERM the recorder (it finishes the bag), SIGKILL after ``timeout``; the bag's info
        (the same again once stopped)."""
        if self.result is not None:
            return self.result
        stop_process(self.process, timeout)
        return self._finish()

    def kill(self) -> None:
        """SIGKILL: the bag keeps every chunk flushed so far, without summary or metadata."""
        self.process.kill()
        self.process.wait()
        self._reader.join(5.0)

    def _finish(self) -> BagInfo:
        self._reader.join(5.0)
        if self.process.returncode not in (0, -signal.SIGTERM):
            raise RuntimeError(
                f"recorder exited {exit_description(self.process.returncode)}: "
                + " | ".join(self.log[-5:])
            )
        self.result = bag_info(self.output)
        return self.result

    def __enter__(self) -> RecorderProcess:
        return self

    def __exit__(self, exc_type, exc, traceback) -> None:
        if exc is None:
            self.stop()
            return
        # leaving on an error: still stop the recorder (and finish the bag if it can), but a
        # failure of its own must not replace the error under way, nor skip later cleanups
        try:
            self.stop()
        except Exception as error:
            exc.add_note(f"and stopping the recorder failed: {error}")


def record_for(
    output: str | os.PathLike,
    seconds: float,
    topics: Iterable[str] | None = None,
    regex: str | None = None,
    **options: object,
) -> BagInfo:
    """Record the selected topics (default: the HEMS graph) for ``seconds`` into ``output``."""
    recorder = RecorderProcess(output, topics, regex, duration=seconds, **options)
    try:
        return recorder.wait(timeout=seconds + 30.0)
    except BaseException:
        recorder.stop()
        raise
