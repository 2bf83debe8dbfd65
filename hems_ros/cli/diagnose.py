"""``hems diagnose``: where the model and measured runs disagree, what is missing, and the
corrected model; ``hems diagnose-suite``: the hidden-effect suite that tests the workflow.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import time
from pathlib import Path

from hems_ros.cli.numbers import non_negative_int, positive, positive_int

DEFAULT_MODEL = "table41"
EPILOG = """\
RUN: a bag folder recorded from the graph (input /hems/<finger>/duty, measurements
  /hems/<finger>/encoder and wire_force; /hems/sim/* is never read), or a table with --columns.
  A measurement that is not a number (a bag's NaN or inf, a table's nan or inf) is dropped
  with a note (more than 5 % of a run: refused); an input outside its range or not a number
  (a duty outside 0-100 %) stops the diagnosis naming topic and message or row (exit 2);
  so does a unit that does not fit (a driven run sampled seconds apart, a duty that never
  exceeds 1 %, a current over 20 A), naming the unit that would.

--columns quantity=column[:unit],... e.g. time=t:s,duty=d:%,displacement=x:mm,force=F:N
  driven run:    time and one of duty, current, voltage in; displacement (contraction
                 positive), strain (elongation positive), wire_force (alias force),
                 load_force, temperature out; an empty cell of a column logged more
                 slowly is filled between its readings, an empty input cell holds
  run in a frame: time, one of duty, current, voltage (or a chamber's temperature, from
                 below the model's As0) and prescribed_strain (elongation positive)
                 in; stress or wire_force out (work loops, tensile tests)
  thermal cycle: temperature in (rows in path order, time optional), stress or load_force
                 (taken row by row where the frame let it wander), strain, extension
                 (over the --model wire's length: the gauge length) or displacement
                 out; rows that still load the wire are left out, and a cycle that
                 starts warm and closes is read from its coldest row
  table of tests: name, pulse_length, current, energy, cooled_displacement, protocol,
                 controller (conditions); peak_displacement, peak_force, cooling_time,
                 overshoot, rise_time, ss_error, rmse, mean_power (figures; blank = not given)
  stress and load over the cross-section of the --model wire (a specimen's diameter and
  gauge length: --conditions with wire: {diameter_m: ..., length_m: ...})
  a load frame's export: lines above the header (test method, sample) are read past, rows
  quoted whole are split, a time printed coarser than the rows come is spread evenly
  units: s ms min h | % 1 | A mA | V mV | degC K | Pa kPa MPa GPa | N kN mN | m mm um in |
         strain 1 or %; a unit left out is SI (temperatures degC, duty %)
"""


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "diagnose",
        help="find where the model and measured data disagree, name the missing effect, fit it",
        description="Replay measured runs on the physics model (the measured input drives it open "
        "loop), localise the residual by phase and cycle, then explain it: first a recalibration "
        "of the printed model's parameters within published NiTi bounds, then missing effects from "
        "a library of candidates, each fitted (bounded least squares) and kept only if it "
        "improves held-out data it was not fitted on; the gap is measured on held-out data "
        "that chose nothing. Writes a report folder (report.md, figures, "
        "corrected.yaml, summary.json) and prints one summary line. Exit 0 whatever the "
        "verdict, 1 if the run failed, 2 for bad input.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("runs", nargs="*", metavar="RUN", help="measured runs to fit on")
    parser.add_argument(
        "--heldout",
        nargs="+",
        default=[],
        metavar="RUN",
        help="runs kept out of the fit: their odd cycles (rows of a table) select the "
        "terms, their even ones test the result. Default: every third cycle or row from the "
        "second selects and, from eight cycles or rows on (three left to fit), every third "
        "from the third tests; with fewer the gap is measured on the selecting data (the "
        "report says so). A separate run recorded with other inputs is the stronger test, and the "
        "only one of an effect that acts at a run's start (a warm wire shows in the first "
        "cycle alone)",
    )
    parser.add_argument(
        "--model",
        default=DEFAULT_MODEL,
        help=f"starting model: a config/physics name or a YAML path (default {DEFAULT_MODEL}, "
        "the dissertation's Table 4.1 wire)",
    )
    parser.add_argument(
        "--conditions",
        type=Path,
        action="append",
        default=[],
        metavar="FILE",
        help="YAML with the run's conditions over the model (load, ambient, drive), in the "
        "layout of config/physics/*.yaml; only the keys it gives change. Once per RUN "
        "(then --heldout RUN, in order): tables of tests measured on different rigs, each "
        "on its own, diagnosing one wire",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        dest="overrides",
        help="one model parameter, e.g. --set load.pretension_n=20 (repeatable)",
    )
    parser.add_argument(
        "--bounds",
        type=Path,
        default=None,
        metavar="FILE",
        help="YAML of parameter ranges replacing the library's, SI units (temperatures degC): "
        "'kinetics.as0_c: [40, 75]', or around the starting model's value "
        "'kinetics.as0_c: {around_model: [15, 15]}'; for a wire outside the dissertation's "
        "band (--list-candidates shows the keys and the library's ranges)",
    )
    parser.add_argument(
        "--timing-range",
        type=positive,
        default=None,
        metavar="S",
        help="largest input delay either way the diagnosis of driven runs searches for, s "
        "(default three sample periods): a logger that stamps each sample with the end of "
        "the period it held, or a loop's latency, is named as timing, not as physics",
    )
    parser.add_argument(
        "--columns",
        action="append",
        default=[],
        help="column mapping of table runs (see below); once for every table, or once per RUN "
        "(then --heldout RUN, in order)",
    )
    parser.add_argument(
        "--fingers", default=None, help="fingers of a bag, comma separated (default: all found)"
    )
    parser.add_argument(
        "--candidates",
        default=None,
        help="comma-separated candidates to consider (default: the whole library; "
        "--list-candidates shows it)",
    )
    parser.add_argument(
        "--list-candidates", action="store_true", help="print the candidate library and exit"
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help="report folder (default results/diagnosis/<first run's name>)",
    )
    parser.add_argument(
        "--dt",
        type=positive,
        default=None,
        help="plant step of the replay, s (default 1 ms; 10 ms for thermal cycles; "
        "2 ms for tables of pulse tests)",
    )
    parser.add_argument(
        "--quiet", action="store_true", help="no progress output, only the summary line"
    )
    parser.add_argument(
        "--each",
        action="store_true",
        help="a lab's archive: diagnose every RUN on its own as well as all of them together "
        "(the shared fit), as tasks on --scheduler; a report per run in OUT/<run>, the shared "
        "one in OUT/all, a table of verdicts in OUT/archive.md",
    )
    add_cluster_options(parser)
    parser.set_defaults(func=run)

    suite = subparsers.add_parser(
        "diagnose-suite",
        help="run the hidden-effect suite of hems diagnose (docs/diagnosis-suite.md)",
        description="Synthetic measurements with a known truth (each candidate effect hidden in "
        "turn, a parameter moved, two effects at once, effects in another form than their "
        "candidate, an effect outside the library, nothing at all), at three sensor-noise levels "
        "on two input profiles, each diagnosed from the starting model; plus the dissertation's "
        "own measurements. Writes suite.md, suite.json and the confusion matrix into --out, and "
        "docs/diagnosis-suite.md with --docs. Seeded: the same seed gives the same result, on any "
        "scheduler. Each finished case is kept in OUT/cases, so a stopped run continues where "
        "it stopped (remove OUT/cases to start afresh).",
    )
    suite.add_argument(
        "--out", type=Path, default=Path("results/diagnosis-suite"), help="output folder"
    )
    suite.add_argument(
        "--seed", type=non_negative_int, default=0, help="seed of the sensor noise (default 0)"
    )
    suite.add_argument(
        "--quick", action="store_true", help="the reduced subset that make test runs"
    )
    suite.add_argument(
        "--docs",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write the generated page (e.g. docs/diagnosis-suite.md)",
    )
    suite.add_argument(
        "--no-dissertation",
        action="store_true",
        help="skip the dissertation's measurements (the synthetic suite only)",
    )
    add_cluster_options(suite)
    suite.set_defaults(func=run_suite)

    blind = subparsers.add_parser(
        "diagnose-blind",
        help="run the blind suite of hems diagnose (docs/diagnosis.md)",
        description="Truths from code the diagnosis never runs (a wire of the dissertation's "
        "law written again or of Brinson's model in the chapter 3 rig with a Bowden sheath, "
        "Dahl friction, a tabulated stiffening spring, a sagging supply under a position loop, "
        "a warm start, a warming load cell, a lagging or drifting encoder, or nothing hidden, "
        "at several sizes), read through sensors with coloured noise, latency and spikes at "
        "three levels, written as a lab's CSV and conditions and diagnosed from table41. "
        "Writes blind.md, blind.json and the detection figure into --out, and the page with "
        "--docs; with --half tuning, tuning.md instead: the search's thresholds against what "
        "the candidates offered (docs/diagnosis-tuning.md). Each finished truth is kept in "
        "OUT/cases, so a stopped run continues where it stopped.",
    )
    blind.add_argument(
        "--out", type=Path, default=Path("results/diagnosis-blind"), help="output folder"
    )
    blind.add_argument(
        "--half",
        choices=("evaluation", "tuning", "all"),  # the halves hems_ros.diagnosis.blind.seeds knows
        default="evaluation",
        help="which seeds: the evaluation half (default, what the page reports), the tuning "
        "half (what thresholds may be set on) or both",
    )
    blind.add_argument("--quick", action="store_true", help="the two truths make test runs")
    blind.add_argument(
        "--docs",
        type=Path,
        default=None,
        metavar="PATH",
        help="also write the page (docs/diagnosis.md, or docs/diagnosis-tuning.md with "
        "--half tuning) and its figure beside it; on the local scheduler the page's scale "
        "section first times a spread of the truths on one worker and on two (about 5 minutes on "
        "two cores)",
    )
    add_cluster_options(blind)
    blind.set_defaults(func=run_blind)


def scheduler(text: str) -> str:
    from hems_ros.diagnosis.cluster import scheduler_error

    if (error := scheduler_error(text)) is not None:
        raise argparse.ArgumentTypeError(error)
    return text


def add_cluster_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--scheduler",
        type=scheduler,
        default="local",
        metavar="WHERE",
        help="where the tasks run: 'local' (default: a Dask LocalCluster of worker processes "
        "on this machine), 'serial' (in this process, no Dask) or the address of a running "
        "Dask scheduler, tcp://HOST:PORT ('dask scheduler' and 'dask worker' started by hand)",
    )
    parser.add_argument(
        "--workers",
        type=positive_int,
        default=None,
        help="worker processes of the local cluster (default: one per core)",
    )


def _say(quiet: bool):
    start = time.perf_counter()

    def say(message: str) -> None:
        if not quiet:
            print(f"[{time.perf_counter() - start:6.1f} s] {message}", file=sys.stderr, flush=True)

    return say


def run(args: argparse.Namespace) -> int:
    from hems_ros.cli import diagnose_archive as archive
    from hems_ros.diagnosis import candidates, inputs
    from hems_ros.diagnosis.runs import DiagnosisInputError
    from hems_ros.diagnosis.workflow import diagnose
    from hems_ros.physics.params import ParamError
    from hems_ros.reports import diagnosis as report

    if args.list_candidates:
        print(candidates.describe_library())
        return 0
    say = _say(args.quiet)
    try:
        if not args.runs:
            raise DiagnosisInputError("no RUN given (a bag folder or a table file with --columns)")
        paths = args.runs + args.heldout
        columns = inputs.per_run("--columns", args.columns, len(paths))
        # one --conditions sets the model; one per run, each run's rig
        shared = args.conditions[0] if len(args.conditions) == 1 else None
        rigs = inputs.per_run("--conditions", [] if shared else args.conditions, len(paths))
        model = inputs.model(args.model, shared, args.overrides)
        chosen = inputs.candidate_names(args.candidates)
        bounds = inputs.bounds(args.bounds)
        loaded = [
            inputs.on_rig(inputs.load(path, cols, args.fingers, model.wire), rig, model)
            for path, cols, rig in zip(paths, columns, rigs)
        ]
        runs = [r for group in loaded[: len(args.runs)] for r in group]
        heldout = [r for group in loaded[len(args.runs) :] for r in group]
        out = args.out or Path("results", "diagnosis", inputs.stem(args.runs[0]))
        inputs.check_output(out)
        options = dict(
            candidates=chosen, bounds=bounds, timing_range_s=args.timing_range, dt=args.dt
        )
        if args.each:
            groups = [(inputs.stem(p), group) for p, group in zip(args.runs, loaded)]
            return archive.diagnose_each(groups, heldout, model, options, out, args, say)
        diagnosis = diagnose(runs, heldout, model, progress=say, **options)
    except (DiagnosisInputError, ParamError) as error:
        print(f"hems diagnose: {error}", file=sys.stderr)
        return 2
    report.write(diagnosis, out)
    say(f"report: {out}")
    print(diagnosis.summary_line())
    return 0


def run_suite(args: argparse.Namespace) -> int:
    from hems_ros.diagnosis import suite_runs
    from hems_ros.reports import diagnosis_suite as suite_report

    say = _say(False)
    runs = suite_runs.run(
        args.out,
        seed=args.seed,
        quick=args.quick,
        dissertation=not args.no_dissertation,
        progress=say,
        scheduler=args.scheduler,
        workers=args.workers,
    )
    result = suite_report.write(runs, args.out, seed=args.seed, quick=args.quick)
    if args.docs is not None:
        _publish(args.docs, result.page, args.out / "confusion.png", "diagnosis_confusion.png")
        say(f"wrote {args.docs}")
    print(result.headline)
    return 0


def run_blind(args: argparse.Namespace) -> int:
    import json
    from functools import partial

    from hems_ros.diagnosis import blind, cluster, speedup
    from hems_ros.reports import blind as page
    from hems_ros.reports import blind_tuning as tuning

    say = _say(False)
    rows = blind.grid(args.quick, args.half)
    tasks = blind.tasks(rows)
    # the page states what a second worker gains here, measured on some of its own tasks
    measured = None
    if args.docs is not None and args.half != "tuning" and args.scheduler == cluster.LOCAL:
        measured = speedup.two_over_one(speedup.spread(tasks), say)
    done = cluster.run_tasks(
        tasks,
        args.out / "cases",
        scheduler=args.scheduler,
        workers=args.workers,
        say=say,
        describe=lambda r: f"{r['verdict']} {','.join(r['named']) or '-'}",
    ).done
    records = blind.scored([d.result for d in done.values()])
    seconds = [d.seconds for d in done.values()]
    (args.out / "blind.json").write_text(json.dumps({"runs": records}, indent=1) + "\n")
    if args.half == "tuning":  # the thresholds against it: what the tuning half is for
        stem, draw, text = "tuning", tuning.figure, partial(tuning.render, records)
    else:
        stem, draw, text = (
            "blind",
            page.figure,
            partial(page.render, records, seconds, measured=measured),
        )
    draw(records, args.out / f"{stem}.png")
    (args.out / f"{stem}.md").write_text(text(f"{stem}.png"))
    if args.docs is not None:
        name = f"diagnosis_{stem}.png"
        _publish(args.docs, text(f"{FIGURES}/{name}"), args.out / f"{stem}.png", name)
        say(f"wrote {args.docs}")
    for label, (right, runs), floor in page.headline(records):
        if runs:
            print(
                f"{label}: {right} of {runs}" + ("" if floor is None else f" (floor {floor:.0%})")
            )
    return 0


FIGURES = "figures"  # beside a generated page, where its figures go


def _publish(page_path: Path, text: str, figure: Path, figure_name: str) -> None:
    """A generated page and its figure into the docs folder (the page links
    ``figures/<figure_name>``)."""
    figures = page_path.parent / FIGURES
    figures.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(figure, figures / figure_name)
    page_path.write_text(text)
