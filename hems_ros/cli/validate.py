"""``hems validate``: run the physics validation and write docs/validation.md + figures.

With ``--calibrate`` the calibrated parameter sets (config/physics/sheathed_calibrated.yaml
and the chapter 5/6 presets) are refitted first (hems_ros.physics.calibration).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "validate",
        help="validate the SMA actuation-unit physics against the dissertation "
        "(docs/validation.md)",
        description="Run the physics validation scenarios (Table 3.2/3.3 pulse sweep with 4 A "
        "pulses in A and s, sheath facts, hanging-mass loops in kg, minor loops, "
        "constant-voltage drive in V) and write a Markdown report with the "
        "dissertation's numbers side by side plus PNG figures.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument(
        "--output",
        "-o",
        type=Path,
        default=Path("docs"),
        help="folder for validation.md; figures go to <output>/figures",
    )
    parser.add_argument(
        "--calibrate",
        action="store_true",
        help="refit C_M=C_A (Pa/degC), eps_L, sheath gap resistance (K/W) and sheath "
        "heat capacity (J/K) and rewrite config/physics/*.yaml before validating",
    )
    parser.add_argument(
        "--physics-config",
        default=None,
        metavar="NAME|PATH",
        help="validate this parameter set (a config/physics name or a YAML path, e.g. the "
        "corrected.yaml of hems diagnose) in place of sheathed_calibrated; write it "
        "somewhere else than docs with --output",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hems_ros.physics import calibration
    from hems_ros.physics.params import ParamError, UnitParams, config_dir, load_params, save_params
    from hems_ros.reports import validation

    start = time.perf_counter()
    params = None
    if args.physics_config is not None:
        try:
            params = load_params(args.physics_config)
        except (ParamError, FileNotFoundError) as error:
            print(
                f"hems validate: --physics-config {args.physics_config}: {error}", file=sys.stderr
            )
            return 2
        if args.calibrate:
            print(
                "hems validate: --calibrate and --physics-config exclude each other",
                file=sys.stderr,
            )
            return 2
    if args.calibrate:
        print(
            f"calibrating (Nelder-Mead over {len(calibration.FREE_PARAMETERS)} parameters, "
            f"about 10 s) ...",
            flush=True,
        )
        count = [0]

        def progress(values, cost):
            count[0] += 1
            if count[0] % 25 == 0:
                print(f"  evaluation {count[0]}: cost {cost:.4f}", flush=True)

        fitted, metrics = calibration.calibrate(UnitParams(), progress=progress)
        for name, params in calibration.presets(fitted).items():
            print(f"  wrote {save_params(params, config_dir() / f'{name}.yaml')}")
    validation.run(args.output, progress=lambda msg: print(msg, flush=True), params=params)
    print(f"done in {time.perf_counter() - start:.1f} s")
    return 0
