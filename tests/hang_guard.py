"""A hung test fails instead of holding the run until CI's overall limit.

At ``HEMS_TEST_HANG_S`` (420 s) the test fails with an exception raised in the main thread, so
its fixtures still clean up. A test stuck inside C code, where that exception cannot land,
stops the whole run when it has run 15 % longer: every thread's stack, the processes it
started killed, and the test's name as the last line of the output. Both need the
interpreter; a call that holds it and never returns (a deadlock inside the middleware) is
stopped by faulthandler's own thread 30 % longer, with every thread's stack.
"""

from __future__ import annotations

import faulthandler
import os
import signal
import sys
import threading
from pathlib import Path

import pytest

HANG_S = float(os.environ.get("HEMS_TEST_HANG_S", "420"))
HARD_STOP_S = 1.15 * HANG_S
LAST_RESORT_S = 1.3 * HANG_S


def live_descendants(root: int) -> dict[int, str]:
    """Processes below ``root`` that still run (zombies left out), with their command lines."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            pid, rest = stat.read_text().split(" (", 1)
            state, ppid = rest.rsplit(") ", 1)[1].split()[:2]
        except (OSError, ValueError):
            continue  # gone while we looked
        if state != "Z":
            children.setdefault(int(ppid), []).append(int(pid))
    found: dict[int, str] = {}
    stack = list(children.get(root, []))
    while stack:
        pid = stack.pop()
        try:
            found[pid] = (
                Path(f"/proc/{pid}/cmdline")
                .read_bytes()
                .replace(b"\0", b" ")
                .decode(errors="replace")
                .strip()
            )
        except OSError:
            continue
        stack.extend(children.get(pid, []))
    return found


def _fail_hung(signum, frame) -> None:
    pytest.fail(f"still running after {HANG_S:g} s: stopped as hung")


def _stop_run(item: pytest.Item) -> None:
    # the test's output is captured into a file that os._exit would leave unread
    capture = item.config.pluginmanager.getplugin("capturemanager")
    if capture is not None:
        capture.suspend_global_capture(in_=False)
    faulthandler.dump_traceback(all_threads=True)
    for pid in live_descendants(os.getpid()):
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    sys.stderr.write(
        f"\nHUNG: {item.nodeid} ran {HARD_STOP_S:g} s and did not stop when failed; "
        "every thread's stack is above. The run stops here.\n"
    )
    sys.stderr.flush()
    os._exit(3)


def _real_stderr(item: pytest.Item) -> int:
    """The run's own stderr behind pytest's capture (a private attribute, else fd 2): the
    last resort cannot suspend the capture, and what it writes into it is lost at the exit."""
    capture = item.config.pluginmanager.getplugin("capturemanager")
    err = getattr(getattr(capture, "_global_capturing", None), "err", None)
    return getattr(err, "targetfd_save", 2)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem):
    previous = signal.signal(signal.SIGALRM, _fail_hung)
    signal.setitimer(signal.ITIMER_REAL, HANG_S)
    hard_stop = threading.Timer(HARD_STOP_S, _stop_run, args=(item,))
    hard_stop.daemon = True
    hard_stop.start()
    faulthandler.dump_traceback_later(LAST_RESORT_S, exit=True, file=_real_stderr(item))
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
        hard_stop.cancel()
