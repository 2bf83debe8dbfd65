"""Graph CPU of this working tree against another commit, side by side in one graph.

The separate-process graph's CPU moves by 10 % and more between runs minutes apart on a
shared host (docs/design.md), more than most changes to a node; runs of two
versions one after the other then compare the host's phases, not the code. Here half of
each node kind runs the other commit's code (``PYTHONPATH`` on a ``git worktree`` of it)
and half this tree's, in one graph, so both halves see the same host; a second run swaps
the halves, so no finger or shoulder module favours either side. Prints the CPU per process
of each node kind for both versions and their ratio. The supervisor (one process) runs this
tree's code in both runs and is left out. The two versions must speak the same messages.

Against ``HEAD`` (the default) with a clean tree both halves run the same code: the ratios
then show the method's own spread.

Usage: .venv/bin/python benchmarks/bench_graph_ab.py [--against REV] [--seconds 30] [--smoke]
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

import smoke
from bench_graph import cpu_by_process  # reserves this run's ROS domain
from host import host_line

from hems_ros.client.graph_client import GraphClient
from hems_ros.graph import names
from hems_ros.launcher import Graph, GraphOptions, warm_physics_cache
from hems_ros.rosenv import child_environment

REPO = Path(__file__).resolve().parents[1]
KINDS = ("actuation_unit", "finger_controller", "shoulder_module")
# the first run's half on the other commit; the second run swaps
FIRST_HALF = {"fingers": ("thumb_flexion", "index", "ring"), "modules": ("thumb", "ring_little")}


@contextmanager
def worktree(rev: str):
    """A detached checkout of ``rev`` in a temporary folder, removed afterwards."""
    sha = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", "--verify", f"{rev}^{{commit}}"],
        capture_output=True,
        text=True,
    )
    if sha.returncode != 0:
        sys.exit(f"bench_graph_ab: {rev!r} is not a commit of {REPO}: {sha.stderr.strip()}")
    with tempfile.TemporaryDirectory(prefix="hems-ab-") as parent:
        path = Path(parent) / "tree"
        subprocess.run(
            [
                "git",
                "-C",
                str(REPO),
                "worktree",
                "add",
                "--detach",
                "--quiet",
                str(path),
                sha.stdout.strip(),
            ],
            check=True,
        )
        try:
            # This tree's kernel compiled ahead of time serves the other tree as well when the
            # physics sources are the same (it checks their hash); else its nodes fall back to
            # numba's JIT kernel, which would otherwise all compile at once at start-up
            for built in (REPO / "hems_ros" / "physics").glob("_kernel_aot*"):
                shutil.copy2(built, path / "hems_ros" / "physics" / built.name)
            warm_physics_cache({**child_environment(), "PYTHONPATH": str(path)})
            yield sha.stdout.strip(), path
        finally:
            subprocess.run(
                ["git", "-C", str(REPO), "worktree", "remove", "--force", str(path)], check=False
            )


def other_half(swapped: bool) -> set[str]:
    """Node names that run the other commit's code."""
    fingers = set(FIRST_HALF["fingers"]) ^ (set(names.FINGERS) if swapped else set())
    modules = set(FIRST_HALF["modules"]) ^ (set(names.MODULES) if swapped else set())
    return (
        {f"actuation_unit_{f}" for f in fingers}
        | {f"finger_controller_{f}" for f in fingers}
        | {f"shoulder_module_{m}" for m in modules}
    )


def run(tree: Path, swapped: bool, seconds: float) -> dict[str, dict[str, list[float]]]:
    """CPU cores of each process by kind and side ('this' or 'other') over ``seconds``."""
    other = other_half(swapped)
    graph = Graph(GraphOptions(composed=False, log_level="error"))
    graph.start(node_env={name: {"PYTHONPATH": str(tree)} for name in other})
    try:
        with GraphClient("hems_bench_ab") as client:
            ok, message = client.enable_when_ready(90, reset=True, retry_s=1.0)
            if not ok:
                sys.exit(f"bench_graph_ab: could not enable the graph: {graph.with_exits(message)}")
            for finger in names.FINGERS:
                client.send_setpoint(finger, "position", 0.010)
            client.spin_for(5.0)
            pids = {name: process.pid for name, process in graph.processes.items()}
            before, start = cpu_by_process(list(pids.values())), time.monotonic()
            client.spin_for(seconds)
            after, elapsed = cpu_by_process(list(pids.values())), time.monotonic() - start
    finally:
        graph.stop()
    result: dict[str, dict[str, list[float]]] = {kind: {"this": [], "other": []} for kind in KINDS}
    for name, pid in pids.items():
        kind = next((k for k in KINDS if name.startswith(k)), None)
        if kind is not None and pid in before and pid in after:
            result[kind]["other" if name in other else "this"].append(
                (after[pid] - before[pid]) / elapsed
            )
    return result


def mean(values: list[float]) -> float:
    return sum(values) / len(values) if values else float("nan")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--against", default="HEAD", help="commit whose code the other half runs (default HEAD)"
    )
    parser.add_argument(
        "--seconds", type=float, default=30.0, help="measured time per run, s (default 30)"
    )
    args = smoke.parse_args(parser, seconds=2.0)
    # a smoke run goes through both halves' code once; the swap only runs it again
    runs = (False,) if args.smoke else (False, True)
    with worktree(args.against) as (sha, tree):
        print(
            f"graph A/B benchmark: this tree against {args.against} ({sha[:8]}), "
            + ("1 run" if args.smoke else "2 runs with the halves swapped")
            + f" x {args.seconds:g} s; {host_line()}",
            flush=True,
        )
        totals: dict[str, dict[str, list[float]]] = {
            kind: {"this": [], "other": []} for kind in KINDS
        }
        for swapped in runs:
            for kind, sides in run(tree, swapped, args.seconds).items():
                for side, values in sides.items():
                    totals[kind][side].extend(values)
            print(f"  run {int(swapped) + 1} of {len(runs)} done", flush=True)
    print(
        f"{'node kind':<18} {'this tree':>10} {sha[:8]:>10} {'ratio':>7}   (CPU cores per "
        f"process, mean)"
    )
    for kind, sides in totals.items():
        this, other = mean(sides["this"]), mean(sides["other"])
        print(f"{kind:<18} {this:>10.4f} {other:>10.4f} {this / other:>7.3f}")
    print("ratio = this tree / the other commit; below 1: this tree takes less CPU")


if __name__ == "__main__":
    main()
