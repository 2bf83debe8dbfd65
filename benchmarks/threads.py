"""CPU and context switches of processes' threads, grouped by what the thread does.

A separate graph's CPU splits into the nodes' main threads, which run Python at every
wake-up, and Fast DDS's threads (its shared-memory listeners wake once per message received);
grouping the threads of many processes by that role shows which of the two a change moves.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass


@dataclass(frozen=True)
class ThreadUse:
    cpu_s: float  # user + system
    switches: int  # voluntary and involuntary context switches: wake-ups, roughly


def _thread_use(pid: int, tid: str) -> tuple[str, ThreadUse] | None:
    try:
        with open(f"/proc/{pid}/task/{tid}/stat") as stat:
            text = stat.read()
        with open(f"/proc/{pid}/task/{tid}/status") as status:
            lines = status.read().splitlines()
    except OSError:
        return None  # the thread ended between the listing and the read
    name = text[text.index("(") + 1 : text.rindex(")")]
    fields = text.rsplit(")", 1)[1].split()
    switches = sum(
        int(line.split()[1])
        for line in lines
        if line.startswith(("voluntary_ctxt_switches", "nonvoluntary_ctxt_switches"))
    )
    cpu_s = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    return name, ThreadUse(cpu_s, switches)


DDS_THREADS = {  # Fast DDS's thread names without their numbers
    "dds.ev": "dds event thread (timers: heartbeats, announcements)",
    "dds.udp": "dds UDP listener (discovery)",
    "dds.shm.wdog": "dds shared-memory watchdog",
    "dds.asyn": "dds asynchronous writer",
}


def thread_group(pid: int, tid: str, name: str, role: str) -> str:
    """The group of a thread: a node's main thread by its process's role, Fast DDS's threads
    by their kind (``dds.shm.50423`` is the shared-memory listener of a participant's own
    port; the 7000-7999 ones listen on the port every participant of the host shares,
    whatever its domain)."""
    if tid == str(pid):
        return f"main thread, {role}"
    if re.fullmatch(r"dds\.shm\.7\d{3}", name):
        return "dds shared-memory listener, host-wide port"
    if re.fullmatch(r"dds\.shm\.\d+", name):
        return "dds shared-memory listener, own port"
    kind = re.sub(r"[.\d]+$", "", name)
    return DDS_THREADS.get(kind, "dds " + kind[4:] if kind.startswith("dds.") else "other threads")


def snapshot(roles: dict[int, str]) -> dict[tuple[int, str], tuple[str, ThreadUse]]:
    """Every live thread of the processes ``roles`` names (pid -> role): its group and use."""
    threads = {}
    for pid, role in roles.items():
        try:
            tids = os.listdir(f"/proc/{pid}/task")
        except OSError:
            continue
        for tid in tids:
            read = _thread_use(pid, tid)
            if read is not None:
                threads[(pid, tid)] = (thread_group(pid, tid, read[0], role), read[1])
    return threads


def by_group(before: dict, after: dict, elapsed_s: float) -> dict[str, tuple[float, float]]:
    """Group -> (cores, switches a second) between two snapshots, threads alive in both."""
    groups: dict[str, tuple[float, float]] = {}
    for key, (group, used) in after.items():
        if key not in before:
            continue
        earlier = before[key][1]
        cpu, switches = groups.get(group, (0.0, 0.0))
        groups[group] = (
            cpu + (used.cpu_s - earlier.cpu_s) / elapsed_s,
            switches + (used.switches - earlier.switches) / elapsed_s,
        )
    return groups


def mean_by_group(windows: list[dict[str, tuple[float, float]]]) -> dict[str, tuple[float, float]]:
    """by_group results of several windows averaged (a group missing from one counts 0)."""
    groups = {g for window in windows for g in window}
    return {
        g: (
            sum(w.get(g, (0.0, 0.0))[0] for w in windows) / len(windows),
            sum(w.get(g, (0.0, 0.0))[1] for w in windows) / len(windows),
        )
        for g in groups
    }


def table(columns: dict[str, dict[str, tuple[float, float]]]) -> list[str]:
    """Markdown rows: each group's cores, switches a second and CPU per switch, one column
    per measured graph (``columns``: title -> by_group result)."""
    titles = list(columns)
    groups = sorted(
        {g for c in columns.values() for g in c},
        key=lambda g: -max(c.get(g, (0.0, 0.0))[0] for c in columns.values()),
    )
    rows = [
        "| threads | " + " | ".join(f"{t}: cores, wakes/s, us/wake" for t in titles) + " |",
        "|---|" + "---|" * len(titles),
    ]
    for group in groups:
        cells = []
        for title in titles:
            cpu, switches = columns[title].get(group, (0.0, 0.0))
            per = f"{cpu / switches * 1e6:.0f}" if switches else "-"
            cells.append(f"{cpu:.3f}, {switches:.0f}, {per}")
        rows.append(f"| {group} | " + " | ".join(cells) + " |")
    return rows
