"""`hems step --sim-time` at --rate 1, 4 and max, composed and separate: the figures, which the
lockstep clock makes independent of the rate and the layout, and the real-time factor each
run reached (simulated seconds per wall second while recording, from the bag's /clock).

Usage: .venv/bin/python benchmarks/bench_sim_rate.py [--fingers index] [--rates 1,4,max]
       [--layouts composed,separate] [--markdown FILE]
       [--smoke]    (--rate max, composed)
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import smoke

from hems_ros.rosenv import (
    apply_network_defaults,
    child_environment,
    use_private_domain,
)

apply_network_defaults()
DOMAIN_LOCK = use_private_domain()

from hems_ros.bag import load_bag  # noqa: E402

FIGURES = re.compile(
    r"step: (\w+): rmse_mm ([\d.]+), overshoot_mm (-?[\d.]+), steady_state_error_mm (-?[\d.]+)"
)


def run(layout: str, rate: str, fingers: str, folder: Path) -> dict:
    command = [
        sys.executable,
        "-m",
        "hems_ros.cli.main",
        "step",
        "--sim-time",
        "--rate",
        rate,
        "--fingers",
        fingers,
        "--log-level",
        "error",
        "--record",
        str(folder),
    ] + (["--composed"] if layout == "composed" else ["--separate"])
    done = subprocess.run(
        command, capture_output=True, text=True, env=child_environment(), timeout=1800
    )
    found = FIGURES.findall(done.stdout)
    if done.returncode != 0 or not found:
        return {"error": (done.stderr.strip().splitlines() or ["no figures"])[-1]}
    clock = load_bag(folder, topics=["/clock"])["/clock"]
    sim = clock["clock.sec"] + 1e-9 * clock["clock.nanosec"]
    wall = clock.log_time_ns * 1e-9
    return {
        "figures": {f: tuple(map(float, v)) for f, *v in found},
        "rtf": float((sim[-1] - sim[0]) / (wall[-1] - wall[0])),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fingers", default="index", help="fingers to step (default index)")
    parser.add_argument(
        "--rates", default="1,4,max", help="comma-separated --rate values (default 1,4,max)"
    )
    parser.add_argument(
        "--layouts", default="composed,separate", help="composed, separate or both (default)"
    )
    parser.add_argument(
        "--markdown", type=Path, default=None, help="also write the table to this file"
    )
    args = smoke.parse_args(parser, rates="max", layouts="composed")
    failed = []
    lines = [
        "| layout | --rate | real-time factor reached | finger | RMSE, mm | overshoot, mm | "
        "steady-state error, mm |",
        "|---|---|---|---|---|---|---|",
    ]
    with tempfile.TemporaryDirectory() as tmp:
        for layout in args.layouts.split(","):
            for rate in args.rates.split(","):
                print(f"{layout}, --rate {rate} ...", flush=True)
                result = run(layout, rate, args.fingers, Path(tmp) / f"{layout}_{rate}")
                if "error" in result:
                    lines.append(f"| {layout} | {rate} | - | - | {result['error']} | | |")
                    failed.append(f"{layout} --rate {rate}")
                    continue
                for finger, (rmse, overshoot, ss_error) in result["figures"].items():
                    lines.append(
                        f"| {layout} | {rate} | {result['rtf']:.2f} | {finger} | {rmse:.3f} | "
                        f"{overshoot:.3f} | {ss_error:.3f} |"
                    )
                print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    print(text)
    if args.markdown is not None:
        args.markdown.write_text(text)
    if failed:
        sys.exit(f"bench_sim_rate: no figures for {', '.join(failed)}")


if __name__ == "__main__":
    main()
