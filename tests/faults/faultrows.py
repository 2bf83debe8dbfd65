"""What the fault matrix measures and writes (tests/faults): its rows, the graph observer and the
Markdown table that ``make test-faults`` puts into docs/reliability.md."""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field

FINGER = "index"
HOLD_M = 0.02
BEGIN, END = "<!-- fault matrix: begin -->", "<!-- fault matrix: end -->"
ROWS: list["Row"] = []


@dataclass
class Row:
    node: str
    fault: str
    zero_duty_ms: float | None  # from the injection until no heating (None: it never stopped)
    fault_ms: float | None  # until the supervisor's FAULT (None: no FAULT)
    message: str
    peak_c: float  # the wire's peak temperature from the injection (simulation truth)
    recovered: str
    expected: str


@dataclass
class Observer:
    """What the graph shows, with the monotonic time the test process received it."""

    drive: list[tuple[float, float]] = field(default_factory=list)  # (t, applied duty %)
    supervisor: list[tuple[float, str, tuple]] = field(default_factory=list)  # (t, state, faults)
    status: list[tuple[float, object]] = field(default_factory=list)
    truth_c: list[tuple[float, float]] = field(default_factory=list)  # (t, wire degC)
    # (t, node's full name, parameter, string value) of every parameter a node changed
    parameters: list[tuple[float, str, str, str]] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def parameter_taken(self, node: str, name: str, value: str, after: float) -> float | None:
        """When ``node`` reported ``name`` changed to ``value`` after ``after``, or None."""
        with self.lock:
            return next(
                (
                    t
                    for t, n, p, v in self.parameters
                    if t >= after and (n, p, v) == (node, name, value)
                ),
                None,
            )

    def since(self, t0: float) -> tuple[list, list, list]:
        with self.lock:
            return (
                [d for d in self.drive if d[0] >= t0],
                [s for s in self.supervisor if s[0] >= t0],
                [s for s in self.status if s[0] >= t0],
            )


def _ms(value: float | None) -> str:
    return "-" if value is None else f"{value:.0f}"


def render(rows: list[Row]) -> str:
    lines = [
        "| node | fault | zero duty, ms | FAULT, ms | supervisor's message | wire peak, degC | "
        "recovery | expected |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r.node} | {r.fault} | {_ms(r.zero_duty_ms)} | {_ms(r.fault_ms)} | "
            f"{r.message or '-'} | {'-' if math.isnan(r.peak_c) else f'{r.peak_c:.0f}'} | "
            f"{r.recovered} | {r.expected} |"
        )
    return "\n".join(lines) + "\n"


def zero_duty_after(
    drive: list[tuple[float, float]], t0: float, end: float, quiet_s: float = 0.2
) -> float | None:
    """ms from ``t0`` until the unit reports 0 % and keeps it for ``quiet_s`` (or to ``end``);
    0 when the unit reports nothing after ``t0`` (a dead unit heats nothing); None if the wire
    was never let go."""
    readings = [(t, duty) for t, duty in drive if t0 <= t <= end]
    if not readings:
        return 0.0
    for i, (t, duty) in enumerate(readings):
        if duty == 0.0 and all(d == 0.0 for u, d in readings[i:] if u <= t + quiet_s):
            return (t - t0) * 1e3
    return None


def first_fault(supervisor: list, t0: float) -> tuple[float | None, str]:
    for t, state, faults in supervisor:
        if t >= t0 and state in ("FAULT", "ESTOP"):
            return (t - t0) * 1e3, "; ".join(faults)
    return None, ""


def finite(value) -> bool:
    return value is not None and math.isfinite(value)
