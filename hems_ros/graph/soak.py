"""What a soak run measures: resident memory per process over time, messages lost in the
recorded bag (gaps in each topic's sequence numbers) and control periods missed (encoder
samples no duty command answered), judged against the soak's limits. Plain Python: the
``hems soak`` verb samples and records, this module judges.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from hems_ros.graph import names

if TYPE_CHECKING:
    from hems_ros.bag.reader import Bag

#: Limits a soak must hold (README, Safety and reliability; docs/reliability.md).
MAX_MEMORY_GROWTH = 0.05
MAX_MISSED_PERIODS = 0.005


def rss_bytes(pid: int) -> int | None:
    """Resident set size of process ``pid`` (None once it has gone)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


@dataclass
class MemoryLog:
    """RSS samples per process: name -> [(t s since the start, bytes)]."""

    samples: dict[str, list[tuple[float, int]]] = field(default_factory=dict)

    def add(self, name: str, t: float, rss: int | None) -> None:
        if rss is not None:
            self.samples.setdefault(name, []).append((t, rss))

    def growth(self, warmup_s: float) -> dict[str, tuple[int, int, float]]:
        """Per process: (RSS at the end of the warm-up, RSS at the end, growth fraction).

        The end is the median of the last quarter of the samples after the warm-up, so one
        garbage-collection peak does not decide it; processes sampled fewer than twice after
        the warm-up are left out."""
        out = {}
        for name, samples in self.samples.items():
            after = [rss for t, rss in samples if t >= warmup_s]
            if len(after) < 2:
                continue
            start = after[0]
            end = int(np.median(after[-max(1, len(after) // 4) :]))
            out[name] = (start, end, (end - start) / start)
        return out


def sequence_losses(sequence: np.ndarray, counted: np.ndarray | None = None) -> tuple[int, int]:
    """(messages missing between consecutive sequence numbers, restarts): a step of 3 lost
    two; a step back (a publisher that started again) starts a new count. ``counted``: per
    message, whether a step ending at it counts (default all)."""
    if len(sequence) < 2:
        return 0, 0
    step = np.diff(sequence.astype(np.int64))
    if counted is not None:
        step = step[np.asarray(counted)[1:]]
    return int(np.sum(step[step > 1] - 1)), int(np.sum(step <= 0))


def bag_losses(bag: Bag, since_ns: int = 0, until_ns: int | None = None) -> dict[str, int]:
    """Messages lost per recorded topic that numbers its messages (a ``sequence`` field),
    in the steps to messages logged in [``since_ns``, ``until_ns``); topics several
    publishers share (commands) are left out."""
    losses = {}
    for topic, data in bag.topics.items():
        if "sequence" not in data.fields or topic.endswith("/commands"):
            continue
        logged = np.asarray(data.log_time_ns)
        counted = (logged >= since_ns) & (logged < (until_ns if until_ns is not None else np.inf))
        losses[topic] = sequence_losses(np.asarray(data["sequence"]), counted)[0]
    return losses


def missed_periods(
    bag: Bag, finger: str, since_ns: int = 0, until_ns: int | None = None
) -> tuple[int, int]:
    """(encoder samples with no duty command answering them, encoder samples) of ``finger``,
    between the first and the last sample a recorded duty command answers, and stamped in
    [``since_ns``, ``until_ns``): a controller answers every sample it receives, so an
    unanswered one is a control period missed."""
    encoder, duty = names.topic(finger, "encoder"), names.topic(finger, "duty")
    if encoder not in bag or duty not in bag or len(bag[duty]) == 0:
        return 0, 0
    samples = bag[encoder]["header.stamp.sec"].astype(np.int64) * 1_000_000_000 + bag[encoder][
        "header.stamp.nanosec"
    ].astype(np.int64)
    answered = bag[duty]["measurement_stamp.sec"].astype(np.int64) * 1_000_000_000 + bag[duty][
        "measurement_stamp.nanosec"
    ].astype(np.int64)
    last = answered.max() if until_ns is None else min(answered.max(), until_ns - 1)
    within = samples[(samples >= max(answered.min(), since_ns)) & (samples <= last)]
    return int(np.sum(~np.isin(within, answered))), len(within)


@dataclass
class SoakResult:
    minutes: float
    grasps: int
    joins: int
    faults: list[str]
    memory: dict[str, tuple[int, int, float]]
    losses: dict[str, int]
    missed: dict[str, tuple[int, int]]  # after the warm-up
    bag: str
    missed_in_warmup: tuple[int, int] = (0, 0)  # start-up and warm-up, all fingers (no limit)
    lost_in_warmup: int = 0  # messages lost in the bag in start-up and warm-up (no limit)

    @property
    def lost(self) -> int:
        return sum(self.losses.values())

    @property
    def missed_fraction(self) -> float:
        missed = sum(m for m, _ in self.missed.values())
        total = sum(n for _, n in self.missed.values())
        return missed / total if total else 0.0

    @property
    def worst_growth(self) -> tuple[str, float]:
        if not self.memory:
            return "-", 0.0
        name = max(self.memory, key=lambda n: self.memory[n][2])
        return name, self.memory[name][2]

    def failures(self) -> list[str]:
        """What broke the soak's limits ([] when it held them)."""
        out = []
        if self.faults:
            out.append(f"{len(self.faults)} faults: {self.faults[0]}")
        if self.lost:
            out.append(f"{self.lost} messages lost in the bag")
        if self.missed_fraction >= MAX_MISSED_PERIODS:
            out.append(
                f"{100 * self.missed_fraction:.2f} % control periods missed "
                f"(limit {100 * MAX_MISSED_PERIODS:g} %)"
            )
        name, growth = self.worst_growth
        if growth >= MAX_MEMORY_GROWTH:
            out.append(
                f"{name} resident memory grew {100 * growth:.1f} % (limit "
                f"{100 * MAX_MEMORY_GROWTH:g} %)"
            )
        return out

    def markdown(self) -> str:
        missed = sum(m for m, _ in self.missed.values())
        total = sum(n for _, n in self.missed.values())
        lines = [
            f"Soak of {self.minutes:g} min: {self.grasps} grasp cycles, {self.joins} command-line "
            f"joins, bag `{self.bag}`.",
            "",
            "| measure | value | limit |",
            "|---|---|---|",
            f"| faults | {len(self.faults)} | 0 |",
            f"| messages lost in the bag after warm-up (sequence gaps) | {self.lost} | 0 |",
            f"| messages lost in the bag in start-up and warm-up | {self.lost_in_warmup} | - |",
            f"| control periods missed after warm-up | {missed} of {total} "
            f"({100 * self.missed_fraction:.3f} %) | < {100 * MAX_MISSED_PERIODS:g} % |",
            f"| control periods missed in start-up and warm-up | {self.missed_in_warmup[0]} of "
            f"{self.missed_in_warmup[1]} | - |",
            f"| worst resident-memory growth after warm-up | {100 * self.worst_growth[1]:+.1f} % "
            f"({self.worst_growth[0]}) | < {100 * MAX_MEMORY_GROWTH:g} % |",
            "",
            "| process | RSS after warm-up, MiB | RSS at the end, MiB | growth |",
            "|---|---|---|---|",
        ]
        for name, (start, end, growth) in sorted(self.memory.items()):
            lines.append(
                f"| {name} | {start / 2**20:.1f} | {end / 2**20:.1f} | {100 * growth:+.1f} % |"
            )
        lossy = {t: n for t, n in self.losses.items() if n}
        if lossy:
            lines += ["", "| topic | messages lost |", "|---|---|"]
            lines += [f"| {t} | {n} |" for t, n in sorted(lossy.items())]
        if self.faults:
            lines += ["", "Faults:", ""] + [f"- {f}" for f in self.faults]
        return "\n".join(lines) + "\n"
