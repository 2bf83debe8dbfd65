"""A new user's first runs, repeated: `make demo` and the README's typical run.

Each demo is `hems demo` (what `make demo` runs after setup): valid when it exits 0 (the
supervisor stayed ENABLED through the grasp and the fingers tracked). Each typical run is
what the README shows, typed as fast as a script types it: `hems up &`, at once `hems enable`,
`hems setpoint index 20 --unit mm`, three seconds of heating, `hems status`, Ctrl-C; valid
when the status shows the supervisor ENABLED. Both print the supervisor's count of stream
gaps while ENABLED (its /diagnostics), whose longest is compared with its loss limit, its
longest quiet (every stream silent at once: its own reception held up, excused in the gaps
beyond the supervisor's quiet_s), and the longest time a unit or controller took to take
ENABLED, compared with the enable grace.

``--busy`` runs a busy loop on one core throughout (``python3 -c "while True: pass"`` at
normal priority: a browser, a compiler, a user's own node). ``--kill-first`` starts one graph
and kills every process of it with SIGKILL before the runs, as a crash or a closed terminal
does: Fast DDS then leaves its shared-memory files in /dev/shm, which nothing here cleans.

Usage: .venv/bin/python benchmarks/bench_first_runs.py [--demos 20] [--typical 20]
       [--separate] [--busy] [--kill-first] [--smoke]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import busy as busy_option
import smoke
from host import host_line

from hems_ros.rosenv import apply_network_defaults, use_private_domain

apply_network_defaults()
DOMAIN_LOCK = use_private_domain()  # no test run or other benchmark shares it

HEMS = [sys.executable, "-m", "hems_ros.cli.main"]
READY = re.compile(r"ready after ([\d.]+) s")
UP_STOP_S = 60  # s from Ctrl-C for `hems up` to end


@dataclass
class Run:
    valid: bool
    detail: str  # why not valid, or ""
    longest_gap_ms: float  # no gap counted: the silence a gap must exceed; 0: not reported
    gap_stream: str  # "-": no gap counted
    limit_ms: float
    ready_s: float | None  # hems up or the demo: from start to every stream present
    take: tuple[float, str, float] | None  # longest take of ENABLED ms, whose, grace ms
    quiet_ms: float  # the supervisor's longest quiet of every stream at once (0: none reported)


def figures(
    report: dict | None,
) -> tuple[float, str, float, tuple[float, str, float] | None, float]:
    """(longest gap ms, whose, loss limit ms, take, quiet ms) for a :class:`Run`, from the
    supervisor's gap figures as `hems status --json` and `hems demo --summary` give them."""
    if report is None:  # no status came (the run is not valid either)
        return 0.0, "not reported", 0.0, None, 0.0
    if report["longest_gap_ms"] is None:
        longest, stream = report["gap_floor_ms"] or 0.0, "-"
    else:
        longest, stream = report["longest_gap_ms"], report["longest_gap_stream"]
    take = (
        (report["enable_taken_ms"], report["enable_taken_by"], report["enable_grace_ms"])
        if report["enable_taken_ms"] is not None and report["enable_grace_ms"] is not None
        else None
    )
    return longest, stream, report["loss_limit_ms"] or 0.0, take, report["longest_quiet_ms"] or 0.0


def demo(layout: list[str], scratch: Path, index: int) -> Run:
    verdict = scratch / f"demo_{index}.json"
    started = time.monotonic()
    process = subprocess.Popen(
        HEMS
        + ["demo", *layout, "--record", str(scratch / f"demo_{index}"), "--summary", str(verdict)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    lines, enabled_s = [], None
    assert process.stdout is not None
    for line in process.stdout:
        lines.append(line)
        if enabled_s is None and line.startswith("demo: ENABLED"):
            enabled_s = time.monotonic() - started
    code = process.wait()
    shutil.rmtree(scratch / f"demo_{index}", ignore_errors=True)
    report = json.loads(verdict.read_text()) if verdict.exists() else None
    if report is not None:
        problem = report["problem"] or ""
    else:  # the demo ended before it could write its verdict: its last words say why
        said = [line.strip() for line in lines if line.strip()]
        problem = f"exit code {code}: {said[-1] if said else 'no output'}"
    longest, stream, limit, take, quiet = figures(report and report["stream_gaps"])
    return Run(
        code == 0, "" if code == 0 else problem, longest, stream, limit, enabled_s, take, quiet
    )


def hems_step(args: list[str], timeout_s: float) -> subprocess.CompletedProcess:
    """One `hems` command; one that outlives ``timeout_s`` is killed and counts as failed."""
    try:
        return subprocess.run(HEMS + args, capture_output=True, text=True, timeout=timeout_s)
    except subprocess.TimeoutExpired as late:
        return subprocess.CompletedProcess(
            late.cmd, -1, "", f"hems {args[0]}: no answer within {timeout_s:g} s"
        )


def typical(layout: list[str]) -> Run:
    up = subprocess.Popen(
        HEMS + ["up", *layout, "--log-level", "warn"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        process_group=0,
    )
    try:
        enable = hems_step(["enable"], timeout_s=120)
        setpoint = hems_step(["setpoint", "index", "20", "--unit", "mm"], timeout_s=60)
        time.sleep(3.0)
        status = hems_step(["status", "--json"], timeout_s=60)
    finally:
        os.killpg(up.pid, signal.SIGINT)
        try:
            output, _ = up.communicate(timeout=UP_STOP_S)
            stopped = True
        except subprocess.TimeoutExpired:
            # a graph that does not stop is this run's failure, not the benchmark's end
            for pid in children(up.pid):
                os.kill(pid, signal.SIGKILL)
            os.killpg(up.pid, signal.SIGKILL)
            output, _ = up.communicate()
            stopped = False
    ready = READY.search(output)
    try:
        document = json.loads(status.stdout)
    except ValueError:  # the status step timed out or crashed
        document = None
    state = document["supervisor"]["state"] if document else None
    valid = enable.returncode == 0 and setpoint.returncode == 0 and state == "ENABLED" and stopped
    # the first step that failed says why (an enable that gave up names the missing streams)
    failed = next((step for step in (enable, setpoint, status) if step.returncode != 0), None)
    detail = [f"supervisor: {state or 'not heard'}"]
    if document and document["supervisor"]["faults"]:
        detail.append("; ".join(document["supervisor"]["faults"]))
    detail += failed.stderr.strip().splitlines()[-1:] if failed is not None else []
    if not stopped:
        detail.append(f"hems up still running {UP_STOP_S} s after Ctrl-C (killed)")
    longest, stream, limit, take, quiet = figures(document and document["stream_gaps"])
    return Run(
        valid,
        "" if valid else "; ".join(detail),
        longest,
        stream,
        limit,
        float(ready.group(1)) if ready else None,
        take,
        quiet,
    )


def children(pid: int) -> list[int]:
    """Direct child processes of ``pid``."""
    found = []
    for task in os.listdir(f"/proc/{pid}/task"):
        with open(f"/proc/{pid}/task/{task}/children") as listing:
            found += [int(child) for child in listing.read().split()]
    return found


def kill_a_graph(layout: list[str]) -> int:
    """Start a graph, wait until it is ready, SIGKILL every process of it (the nodes first:
    killed, the launcher would stop them cleanly); the Fast DDS files they left."""
    before = set(os.listdir("/dev/shm"))
    up = subprocess.Popen(HEMS + ["up", *layout, "--log-level", "error"], process_group=0)
    subprocess.run(HEMS + ["wait"], capture_output=True, timeout=120)
    for pid in children(up.pid):
        os.kill(pid, signal.SIGKILL)
    up.kill()
    up.wait()
    time.sleep(1.0)
    return len(set(os.listdir("/dev/shm")) - before)


def summary(kind: str, runs: list[Run]) -> str:
    valid = sum(r.valid for r in runs)
    reported = [r for r in runs if r.longest_gap_ms > 0] or runs
    counted = [r for r in reported if r.gap_stream != "-"]
    worst = max(counted or reported, key=lambda r: r.longest_gap_ms)
    ready = [r.ready_s for r in runs if r.ready_s is not None]
    ready_text = f"{statistics.median(ready):.1f} / {max(ready):.1f}" if ready else "-"
    if worst.longest_gap_ms > 0:
        margin = f"{'' if counted else '> '}{worst.limit_ms / worst.longest_gap_ms:.1f}"
    else:
        margin = "-"
    takes = [r.take for r in runs if r.take is not None]
    take_text = "-"
    if takes:
        ms, whose, grace = max(takes)
        take_text = f"{ms:.0f} ms ({whose}) | {grace:.0f} ms | {grace / ms:.1f}"
    quiet = max(r.quiet_ms for r in runs)
    return (
        f"| {kind} | {len(runs)} | {valid} | {ready_text} | {gap_text(worst)} | "
        f"{worst.limit_ms:.0f} ms | {margin} | {f'{quiet:.0f} ms' if quiet else '-'} | "
        f"{take_text} |"
    )


def gap_text(run: Run) -> str:
    if run.longest_gap_ms <= 0:
        return run.gap_stream
    if run.gap_stream == "-":
        return f"none over {run.longest_gap_ms:.0f} ms"
    return f"{run.longest_gap_ms:.0f} ms ({run.gap_stream})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--demos", type=int, default=20, help="demo runs (default 20)")
    parser.add_argument("--typical", type=int, default=20, help="typical runs (default 20)")
    parser.add_argument(
        "--separate", action="store_true", help="the 16 nodes in separate processes"
    )
    busy_option.add_option(parser)
    parser.add_argument("--kill-first", action="store_true", help="SIGKILL a graph before the runs")
    args = smoke.parse_args(parser, demos=0, typical=1)
    layout = ["--separate"] if args.separate else []
    busy = busy_option.start(args)
    scratch = Path(tempfile.mkdtemp(prefix="hems_bench_first_runs_"))
    try:
        conditions = [
            "separate processes" if args.separate else "default layout",
            "busy loop on one core" if args.busy else "no other load",
        ]
        if args.kill_first:
            conditions.append(
                f"after a killed graph ({kill_a_graph(layout)} files left in /dev/shm)"
            )
        print(
            f"first runs: {', '.join(conditions)}; "
            f"/dev/shm holds {len(os.listdir('/dev/shm'))} files; {host_line()}",
            flush=True,
        )
        results = {}
        for kind, count, one in (
            ("make demo", args.demos, lambda i: demo(layout, scratch, i)),
            ("typical run", args.typical, lambda i: typical(layout)),
        ):
            runs = []
            for i in range(count):
                run = one(i)
                runs.append(run)
                print(
                    f"  {kind} {i + 1}/{count}: "
                    f"{'valid' if run.valid else 'NOT VALID: ' + run.detail}"
                    f"; longest gap {gap_text(run)}"
                    + (f"; supervisor quiet {run.quiet_ms:.0f} ms" if run.quiet_ms else "")
                    + (f"; ENABLED taken within {run.take[0]:.0f} ms" if run.take else "")
                    + (f"; ready after {run.ready_s:.1f} s" if run.ready_s else ""),
                    flush=True,
                )
            if runs:
                results[kind] = runs
        print(
            "| run | runs | valid | ready s (median / max) | longest gap (stream) | loss limit "
            "| limit / gap | longest supervisor quiet | longest take of ENABLED | enable grace "
            "| grace / take |"
        )
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        for kind, runs in results.items():
            print(summary(kind, runs))
        print(f"after the runs: {host_line()}")
    finally:
        if busy is not None:
            busy.kill()
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    main()
