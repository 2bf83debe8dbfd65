"""Fast DDS shared-memory files whose owner process is gone (Linux, /dev/shm).

A Fast DDS participant keeps a segment (``fastdds_<16 hex>``) and opens ports
(``fastdds_port<N>``) there, and holds a lock on each one's lock file (``_el``: the exclusive
reader, ``_sl``: shared readers) while it lives. A process killed by SIGKILL, OOM or a crash
leaves its files behind, and the port numbers come back with the next graph of the same
domain. Fast DDS then opens the stale port, checks its health and may replace it while another
process keeps the old one open, and two processes may never hear each other (Fast DDS's reports
"The shared memory mode cannot communicate after restarting the process" and "FastDDS nodes
cannot communicate if another user run node in the past"). A file is an orphan when no process
holds any of its lock files; removing those is what ``fastdds shm clean`` does, and it leaves
the files of live processes (other graphs, other ROS programs) alone.

A port also outlives its lock files: a process that wrote to it keeps it open after its owner
has gone, and one killed then leaves it with no lock file at all (tens of them on a host that
runs tests). Such a port is not recreated but reused by the next owner of its number, with the
settings of its first creator (the shared-memory health check, whose third is how long its
listener sleeps: 333 ms where Fast DDS's default made it); it is an orphan when no live process
maps it.
"""

from __future__ import annotations

import fcntl
import os
import re
import time
from contextlib import ExitStack
from pathlib import Path

SHM_DIR = Path("/dev/shm")
_LOCK_FILE = re.compile(r"^(fastdds_(?:port\d{1,5}|[0-9a-z]{16}))_(?:el|sl)$")
_PORT = re.compile(r"^fastdds_port\d{1,5}$")
_PROC = Path("/proc")
#: A participant creates its lock file and then locks it: a younger file may be one that a
#: starting process has not locked yet.
MIN_AGE_S = 5.0


def _age_s(path: Path) -> float:
    try:
        return time.time() - path.stat().st_mtime
    except OSError:
        return 0.0


def _take(path: Path):
    """The lock file ``path`` open and locked by this process, or None where a live process
    holds it (or it is gone)."""
    try:
        f = path.open("rb")
    except OSError:
        return None
    try:
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        f.close()
        return None
    return f


def remove_orphans(directory: Path = SHM_DIR, min_age_s: float = MIN_AGE_S) -> int:
    """Remove the Fast DDS segments and ports of ``directory`` that no live process holds and
    whose lock files are at least ``min_age_s`` old, and the ports without lock files at least
    that old that no live process maps; how many files went. Nothing to do (0) where the
    directory does not exist."""
    try:
        names = os.listdir(directory)
    except OSError:
        return 0
    locks: dict[str, list[str]] = {}
    for name in names:
        if (match := _LOCK_FILE.match(name)) is not None:
            locks.setdefault(match.group(1), []).append(name)
    removed = 0
    for base, lock_names in sorted(locks.items()):
        if any(_age_s(directory / name) < min_age_s for name in lock_names):
            continue
        with ExitStack() as held:
            taken = [_take(directory / name) for name in lock_names]
            for f in taken:
                if f is not None:
                    held.enter_context(f)
            if None in taken:
                continue
            # the locks stay taken while the files go, so that no process opens them between
            # the test and the removal; a port's named mutex goes with it: one left taken by a
            # killed opener would make the next opener wait for it to time out and reset it
            mutex = [f"sem.{base}_mutex"] if "_port" in base else []
            removed += _unlink(directory, [base, *lock_names, *mutex])
    lockless = [
        name
        for name in names
        if _PORT.match(name) and name not in locks and _age_s(directory / name) >= min_age_s
    ]
    if lockless:
        mapped = _mapped(directory)
        for name in lockless:
            if name not in mapped:
                removed += _unlink(directory, [name, f"sem.{name}_mutex"])
    return removed


def _unlink(directory: Path, names: list[str]) -> int:
    removed = 0
    for name in names:
        try:
            (directory / name).unlink()
            removed += 1
        except FileNotFoundError:
            pass
    return removed


def _mapped(directory: Path) -> set[str]:
    """Names of the files of ``directory`` that a live process has mapped (its /proc maps)."""
    prefix = f"{directory}/"
    mapped = set()
    for entry in _PROC.iterdir() if _PROC.is_dir() else ():
        if not entry.name.isdigit():
            continue
        try:
            maps = (entry / "maps").read_text()
        except OSError:  # gone meanwhile, or not ours to read
            continue
        for line in maps.splitlines():
            _, found, path = line.partition(prefix)
            if found:
                mapped.add(path.removesuffix(" (deleted)"))
    return mapped
