"""``hems tune``: BPID gains tuned on the model for one chapter 5 protocol."""

from __future__ import annotations

import argparse
import time
from datetime import datetime
from pathlib import Path

from hems_ros.cli.numbers import non_negative, positive_int
from hems_ros.experiments.dissertation import CH5_PROTOCOLS, CH6_POSITION


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "tune",
        help="tune BPID gains on the model (scipy Nelder-Mead) and compare with Table 5.1",
        description="Tune the BPID gains Kp (%/um), Kd (% s/um), Kb (1/um) and optionally Ki "
        "(%/(um s)) on the model for one protocol (plant 1 kHz, control 100 Hz), minimising "
        "RMSE (mm) + weight x MACSI (% per sample); then report RMSE, MACSI and APC (W) of "
        "Table 5.1 and tuned gains on every reference of the protocol's rig: a ch5_ protocol "
        "runs the chapter 5 rig (40 N mass, five references), a ch6_position_ one the HEMS "
        "index unit the node graph simulates (four references; RMSE on their ascending or "
        "stationary parts).",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument(
        "--protocol",
        choices=CH5_PROTOCOLS + CH6_POSITION,
        default="ch5_step",
        help="protocol the cost is measured on",
    )
    parser.add_argument(
        "--macsi-weight",
        type=non_negative,
        default=0.1,
        help="weight of MACSI (%% per sample) against RMSE (mm) in the cost",
    )
    parser.add_argument(
        "--with-ki", action="store_true", help="also tune Ki (Table 5.1 has Ki = 0)"
    )
    parser.add_argument(
        "--max-evaluations",
        type=positive_int,
        default=120,
        help="closed-loop simulations the optimiser may spend",
    )
    parser.add_argument(
        "--write-params",
        type=Path,
        default=None,
        metavar="FILE",
        help="also write the tuned gains as a ROS params file for the finger controllers "
        "(run the graph with them: hems up --extra-params FILE)",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hems_ros.experiments.tuning import compare, params_file_text, rig, tune_bpid

    if args.write_params is not None:
        args.write_params.parent.mkdir(
            parents=True, exist_ok=True
        )  # a bad folder stops before the tuning
    start = time.perf_counter()
    print(
        f"tuning BPID on {args.protocol} with physics set {rig(args.protocol)[0]} "
        f"(cost = RMSE mm + {args.macsi_weight} x MACSI) ...",
        flush=True,
    )

    def progress(n, g, cost):
        if n % 10 == 0:
            print(
                f"  evaluation {n}: Kp {g.kp:.3g} Ki {g.ki:.3g} Kd {g.kd:.3g} Kb {g.kb:.3g} "
                f"cost {cost:.3f}",
                flush=True,
            )

    tuned, before, after = tune_bpid(
        args.protocol, args.macsi_weight, args.with_ki, args.max_evaluations, progress
    )
    print(
        f"tuned: Kp {tuned.kp:.4g} %/um, Ki {tuned.ki:.4g} %/(um s), Kd {tuned.kd:.4g} % s/um, "
        f"Kb {tuned.kb:.4g} 1/um; cost {before:.3f} -> {after:.3f}"
    )
    print(
        "\n| reference | RMSE mm Table 5.1 / tuned | MACSI % Table 5.1 / tuned | APC W "
        "Table 5.1 / tuned |"
    )
    print("|---|---|---|---|")
    for p, a, b in compare(tuned, args.protocol):
        print(
            f"| {p} | {a['rmse']:.3f} / {b['rmse']:.3f} | {a['macsi']:.2f} / {b['macsi']:.2f} | "
            f"{a['apc_w']:.1f} / {b['apc_w']:.1f} |"
        )
    if args.write_params is not None:
        command = (
            f"hems tune --protocol {args.protocol} --macsi-weight {args.macsi_weight:g} "
            f"--max-evaluations {args.max_evaluations}{' --with-ki' if args.with_ki else ''}"
        )
        note = (
            f"BPID position-mode gains from `{command}` ({datetime.now():%Y-%m-%d %H:%M}),\n"
            f"tuned on physics set {rig(args.protocol)[0]} for {args.protocol}: cost (RMSE mm "
            f"+ {args.macsi_weight:g} x MACSI) {before:.3f} -> {after:.3f}.\nApply over "
            f"config/hems.yaml: hems up --extra-params {args.write_params}"
        )
        args.write_params.write_text(params_file_text(tuned, note))
        print(f"wrote {args.write_params} (hems up --extra-params {args.write_params})")
    print(f"done in {time.perf_counter() - start:.1f} s")
    return 0
