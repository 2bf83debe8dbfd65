"""Diagnosis speed benchmark: a 120 s one-finger bag through `hems diagnose` with the full library.

Requirement: a 120 s bag of one finger sampled at 100 Hz is diagnosed with the full candidate
library in under 60 s on this two-core machine; the ratio to the run's length is printed.

Input: a real bag in the rosbag2/MCAP layout (hems_ros.bag.BagWriter, CDR bytes from the
installed .msg definitions, no rclpy) in a temporary folder, holding what the recorder takes
from a one-finger graph (index): /hems/index/encoder, wire_force, duty, setpoint and
controller_status, /hems/sim/index/wire_tension (100 Hz) and state (20 Hz), stamps on a 10 ms
grid, each duty's measurement_stamp the stamp of the encoder sample it answers, log times a
fraction of a millisecond after the stamps. The data come from the physics, deterministically:
the truth is ch6_hems_index with a hidden effect (load damping 260 N s/m instead of 65) under
the duty a BPID position loop gives it (experiments.lockstep.simulate_loop) on 8 cycles of
0 -> 10 mm (wire side) -> 0, 15 s each; the truth is then replayed with that duty through the
batch API (dt 1 ms, every 10th step recorded) and read by an encoder of 1 um and a force
sensor with 0.03 N noise quantised to 0.01 N.

Measured, side by side in one run (median of --repeat runs after one untimed run, which also
pays numba's compile-cache load and the first imports): loading the bag (load_bag_runs);
preparing the data and the starting model's replay alone (what every model evaluation costs);
the whole diagnosis, diagnose([run], [], ch6_hems_index) with candidates=None. Light wrappers
around the dataset's predict, the replay's batch simulation, search.fit_structures and the
barrier count the model evaluations, parameter sets and rounds, and say where the time goes
(their overhead is microseconds per call). The diagnosis is timed as shipped (the fits hold
BLAS to one thread: each fit's least squares runs in a thread of its own, two dozen at once),
then once with the BLAS threads left at their default, which shows why. Prints measured numbers
and ratios; the exit code does not depend on the timings.

Run: python benchmarks/bench_diagnose.py [--repeat N] [--cycles N] [--smoke]
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import statistics
import sys
import tempfile
import threading
import time
from collections import namedtuple
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numba
import numpy as np
import smoke

from hems_ros.bag import BagWriter, offered_qos
from hems_ros.codec import cdr, msgdefs
from hems_ros.diagnosis import batching, dataset, replay, search
from hems_ros.diagnosis import candidates as library
from hems_ros.diagnosis import fit as fit_module
from hems_ros.diagnosis.bagload import load_bag_runs
from hems_ros.diagnosis.workflow import Diagnosis, diagnose, prepare
from hems_ros.experiments.lockstep import simulate_loop
from hems_ros.graph import names
from hems_ros.physics import load_params, rows, sensors, simulate

GOAL_S = 60.0  # for a 120 s bag; a shorter one (--cycles) is held to the same ratio
GOAL_RUN_S = 120.0
FINGER = "index"
MODEL = "ch6_hems_index"
HIDDEN = {"load.damping_n_s_per_m": 260.0}
SAMPLE_S = 0.01
DT = 1e-3
LEVEL_M = 10e-3  # wire side
CYCLE_S = (1.0, 6.0, 8.0)  # at rest, holding LEVEL_M, cooling back: 15 s
CYCLES = 8
FORCE_NOISE_N = 0.03
FORCE_SEED = 7
STATUS_EVERY = 2  # controller status with every 2nd duty (finger_controller default)
STATE_EVERY = 5  # simulation truth at 20 Hz (actuation_unit state_period_s 0.05)
# A wall-clock graph stamps in ns since the epoch; start on the 10 ms grid.
T0_NS = 1_750_000_000 * 1_000_000_000
# Reception after the source stamp, as the recorder logs it; the duty is computed from the
# encoder sample and published a little later, the sensor's force relayed by the shoulder module.
LAG_NS = {
    "encoder": 150_000,
    "wire_tension": 180_000,
    "wire_force": 450_000,
    "duty": 700_000,
    "controller_status": 800_000,
    "state": 250_000,
}
DUTY_COMPUTE_NS = 400_000
TRANSPORT_NS = 100_000  # publish to reception: the recorder keeps the writer's time as publish time
SETPOINT_LEAD_NS = 3_000_000  # a setpoint arrives a few ms before the control step that uses it


# --------------------------------------------------------------------------- the input bag
def reference(cycles: int) -> np.ndarray:
    """Wire-side position reference per 10 ms control sample."""
    rest, hold, cool = (int(round(s / SAMPLE_S)) for s in CYCLE_S)
    one = np.concatenate([np.zeros(rest), np.full(hold, LEVEL_M), np.zeros(cool)])
    return np.tile(one, cycles)


@dataclass
class Truth:
    """What the graph would have published, per 10 ms sample."""

    reference: np.ndarray
    duty: np.ndarray
    counts: np.ndarray
    position: np.ndarray
    tension: np.ndarray  # true wire force (the simulation's wire_tension topic)
    force: np.ndarray  # the force sensor's reading
    saturated: np.ndarray
    channels: dict[str, np.ndarray] = field(default_factory=dict)  # kernel channels per sample


def make_truth(cycles: int) -> Truth:
    truth = load_params(MODEL).replace(HIDDEN)
    ref = reference(cycles)
    _, duty, *_, fault = simulate_loop(ref, "bpid", "position", truth)
    if fault is not None or duty.size != ref.size:
        raise SystemExit(f"closed loop stopped early: {fault}")
    sub = int(round(SAMPLE_S / DT))
    res = simulate(truth, DT, duty=np.repeat(duty, sub), record_every=sub)
    # sample k is read before duty k is applied: sample 0 is the initial state, sample k the
    # state after k control periods (record k - 1)
    state0 = rows.initial_state(truth)
    first = {name: state0[rows.STATE_NAMES.index(name)] for name in rows.STATE_NAMES}
    first.update(
        wire_force_n=truth.wire.cross_section_m2 * state0[rows.S_SIG],
        resistance_ohm=0.0,
        current_a=0.0,
        electrical_power_w=0.0,
        tendon_force_n=truth.load.static_force_n(),
        tendon_position_m=0.0,
    )
    channels = {name: np.concatenate([[first[name]], res[name][0][:-1]]) for name in first}
    enc = truth.encoder
    counts = sensors.encoder_counts_array(channels["slider_position_m"], enc.resolution_m, enc.gain)
    noise = np.random.default_rng(FORCE_SEED).standard_normal(ref.size) * FORCE_NOISE_N
    fs = truth.force_sensor
    force, saturated = sensors.force_reading_array(
        channels["wire_force_n"], noise, fs.range_max_n, fs.resolution_n
    )
    return Truth(
        ref,
        duty,
        counts,
        counts * enc.resolution_m,
        channels["wire_force_n"],
        force,
        saturated,
        channels,
    )


def encoders() -> dict[str, tuple[type, Callable[[tuple], bytes]]]:
    """Per message type: a named tuple of its leaf fields (nested names joined by ``_``, as
    hems_ros.ros.wire names them) and the CDR encoder of such a tuple."""
    out: dict[str, tuple[type, Callable[[tuple], bytes]]] = {}
    for name in (
        "EncoderReading",
        "WireForce",
        "DutyCommand",
        "FingerSetpoint",
        "ControllerStatus",
        "ActuatorState",
    ):
        type_name = f"hems_msgs/msg/{name}"
        types = msgdefs.parse_full_definition(type_name, msgdefs.full_definition(type_name))
        encoder = cdr.build_encoder(type_name, types)
        columns = [c.name.replace(".", "_") for c in encoder.columns]
        out[name] = (namedtuple(name, columns), encoder.encode)
    return out


def write_bag(folder: Path, t: Truth) -> int:
    """The recorder's bag of ``t``; returns the number of messages."""
    enc = encoders()
    sensor_qos = [offered_qos(False, False, 10)]
    command_qos = [offered_qos(True, False, 10)]
    topics = {
        "encoder": (names.topic(FINGER, "encoder"), "EncoderReading", sensor_qos),
        "wire_force": (names.topic(FINGER, "wire_force"), "WireForce", sensor_qos),
        "duty": (names.topic(FINGER, "duty"), "DutyCommand", command_qos),
        "setpoint": (names.topic(FINGER, "setpoint"), "FingerSetpoint", command_qos),
        "controller_status": (
            names.topic(FINGER, "controller_status"),
            "ControllerStatus",
            sensor_qos,
        ),
        "wire_tension": (names.sim_topic(FINGER, "wire_tension"), "WireForce", sensor_qos),
        "state": (names.sim_topic(FINGER, "state"), "ActuatorState", sensor_qos),
    }
    period_ns = int(round(SAMPLE_S * 1e9))
    model = load_params(MODEL)
    ratio, wire_length, resolution = (
        model.load.pulley_ratio,
        model.wire.length_m,
        model.encoder.resolution_m,
    )
    c = t.channels
    messages: list[tuple[int, str, bytes]] = []

    def add(stream: str, log_ns: int, stamp_ns: int, **values) -> None:
        """A message of ``stream`` with its header stamped ``stamp_ns``, logged at ``log_ns``;
        every other field by name (a field the definition gained stops the benchmark)."""
        fields, encode = enc[topics[stream][1]]
        sec, nsec = divmod(stamp_ns, 1_000_000_000)
        values.update(header_stamp_sec=sec, header_stamp_nanosec=nsec, header_frame_id="")
        messages.append((log_ns, stream, encode(fields(**values))))

    previous = None
    for k in range(t.duty.size):
        at = T0_NS + k * period_ns
        sec, nsec = divmod(at, 1_000_000_000)
        seq = k + 1
        if t.reference[k] != previous:
            # `hems setpoint` stamps the header with its clock when it publishes
            add(
                "setpoint",
                at - SETPOINT_LEAD_NS + 300_000,
                at - SETPOINT_LEAD_NS,
                mode="position",
                value=float(t.reference[k] * ratio),
            )
            previous = t.reference[k]
        add(
            "encoder",
            at + LAG_NS["encoder"],
            at,
            finger=FINGER,
            counts=int(t.counts[k]),
            position=float(t.position[k]),
            resolution=resolution,
            # the drive board's measurement of the period that ended (current and voltage are
            # not simulated here: the diagnosis takes the commanded duty)
            duty_percent=float(t.duty[k - 1] if k else 0.0),
            on_current=math.nan,
            on_voltage=math.nan,
            sequence=seq,
        )
        add(
            "wire_tension",
            at + LAG_NS["wire_tension"],
            at,
            finger=FINGER,
            force=float(t.tension[k]),
            saturated=False,
            over_force=False,
            sequence=seq,
        )
        add(
            "wire_force",
            at + LAG_NS["wire_force"],
            at,
            finger=FINGER,
            force=float(t.force[k]),
            saturated=bool(t.saturated[k]),
            over_force=False,
            sequence=seq,
        )
        add(
            "duty",
            at + LAG_NS["duty"],
            at + DUTY_COMPUTE_NS,
            finger=FINGER,
            duty_percent=float(t.duty[k]),
            measurement_stamp_sec=sec,
            measurement_stamp_nanosec=nsec,
            sequence=seq,
        )
        if k % STATUS_EVERY == STATUS_EVERY - 1:
            add(
                "controller_status",
                at + LAG_NS["controller_status"],
                at + DUTY_COMPUTE_NS,
                finger=FINGER,
                strategy="bpid",
                mode="position",
                active=True,
                setpoint=float(t.reference[k] * ratio),
                measurement=float(t.position[k] * ratio),
                error=float((t.reference[k] - t.position[k]) * ratio),
                duty_percent=float(t.duty[k]),
                fault="",
                encoder_stamp_sec=sec,
                encoder_stamp_nanosec=nsec,
                wire_position=float(t.position[k]),
                force_stamp_sec=sec,
                force_stamp_nanosec=nsec,
                wire_force=float(t.force[k]),
                rejected_setpoints=0,
                last_rejection="",
                wire_temperature_c=float(c["wire_temperature_c"][k]),
                thermal_limited=False,
                sequence=seq // STATUS_EVERY,
            )
        if k % STATE_EVERY == 0:
            x = float(c["slider_position_m"][k])
            add(
                "state",
                at + LAG_NS["state"],
                at,
                finger=FINGER,
                duty_percent=float(t.duty[k - 1] if k else 0.0),
                watchdog_tripped=False,
                heating_allowed=True,
                wire_temperature_c=float(c["wire_temperature_c"][k]),
                martensite_fraction=float(c["martensite_fraction"][k]),
                resistance=float(c["resistance_ohm"][k]),
                current=float(c["current_a"][k]),
                electrical_power=float(c["electrical_power_w"][k]),
                electrical_energy=float(c["energy_joule_j"][k]),
                stress=float(c["stress_pa"][k]),
                strain=x / wire_length,
                sheath_temperature_c=float(c["sheath_temperature_c"][k]),
                slider_position=x,
                slider_velocity=float(c["slider_velocity_m_s"][k]),
                tendon_position=float(c["tendon_position_m"][k]),
                tendon_force=float(c["tendon_force_n"][k]),
                wire_force=float(c["wire_force_n"][k]),
                sequence=k // STATE_EVERY + 1,
            )
    messages.sort(key=lambda m: m[0])  # the recorder writes in order of reception
    with BagWriter(folder) as writer:
        channel = {
            s: writer.add_topic(topic, f"hems_msgs/msg/{kind}", qos)
            for s, (topic, kind, qos) in topics.items()
        }
        for log_ns, stream, data in messages:
            writer.write(channel[stream], log_ns, data, log_ns - TRANSPORT_NS)
    return len(messages)


# --------------------------------------------------------------------------- instrumentation
class Probe:
    """Counts and times the diagnosis's model evaluations without touching the library."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.reset()

    def reset(self) -> None:
        self.predict_calls = self.predict_sets = 0
        self.predict_s = 0.0
        self.sim_calls = self.sim_sets = 0
        self.sim_s = 0.0
        self.fits: list[tuple[int, float]] = []  # (structures, seconds) per fit_structures call
        self.rounds = 0

    def install(self) -> None:
        probe = self
        predict = dataset.TimeSeriesData.predict
        sim = replay.simulate
        fit_structures = search.fit_structures
        run = batching.Barrier.run

        def timed_predict(self, sets):
            start = time.perf_counter()
            try:
                return predict(self, sets)
            finally:
                with probe.lock:
                    probe.predict_calls += 1
                    probe.predict_sets += len(sets)
                    probe.predict_s += time.perf_counter() - start

        def timed_simulate(params, *args, **kwargs):
            start = time.perf_counter()
            try:
                return sim(params, *args, **kwargs)
            finally:
                with probe.lock:
                    probe.sim_calls += 1
                    probe.sim_sets += len(params)
                    probe.sim_s += time.perf_counter() - start

        def timed_fit(data, base, structures, *args, **kwargs):
            start = time.perf_counter()
            try:
                return fit_structures(data, base, structures, *args, **kwargs)
            finally:
                probe.fits.append((len(structures), time.perf_counter() - start))

        def counted_run(self, jobs):
            try:
                return run(self, jobs)
            finally:
                probe.rounds += self.rounds

        dataset.TimeSeriesData.predict = timed_predict  # type: ignore[method-assign]
        replay.simulate = timed_simulate
        search.fit_structures = timed_fit
        batching.Barrier.run = counted_run  # type: ignore[method-assign]


def median_time(fn, repeat: int):
    """(median wall seconds, the last result)."""
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


@dataclass
class Timing:
    """The median of ``repeat`` diagnoses and what the probe saw in it."""

    walls: list[float]
    wall: float
    cpu: float
    calls: int
    sets: int
    predict_s: float
    sim_calls: int
    sim_sets: int
    sim_s: float
    fits: list[tuple[int, float]]
    rounds: int
    result: Diagnosis


def time_diagnosis(run, model, repeat: int, probe: Probe) -> Timing:
    rows = []
    for _ in range(repeat):
        probe.reset()
        start, cpu = time.perf_counter(), time.process_time()
        result = diagnose([run], [], model)
        rows.append(
            (
                time.perf_counter() - start,
                time.process_time() - cpu,
                probe.predict_calls,
                probe.predict_sets,
                probe.predict_s,
                probe.sim_calls,
                probe.sim_sets,
                probe.sim_s,
                list(probe.fits),
                probe.rounds,
                result,
            )
        )
    walls = [r[0] for r in rows]
    mid = sorted(rows, key=lambda r: r[0])[len(rows) // 2]
    return Timing(walls, *mid)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--repeat", type=int, default=3, help="timed diagnoses per configuration (median printed)"
    )
    parser.add_argument(
        "--cycles", type=int, default=CYCLES, help=f"position steps in the bag (default {CYCLES})"
    )
    args = smoke.parse_args(parser, repeat=1, cycles=2)
    # the medians of the parts (load, prepare, replay): a smoke run times each once
    few, more = (1, 1) if args.smoke else (3, 5)
    model = load_params(MODEL)
    cores = os.cpu_count() or 1
    print(
        f"diagnosis benchmark: {args.cycles} x {sum(CYCLE_S):g} s position steps 0 -> "
        f"{LEVEL_M * 1e3:g} mm (wire side) of the {FINGER} finger, truth {MODEL} with "
        + ", ".join(f"{k} {v:g}" for k, v in HIDDEN.items())
        + f" (model {model.load.damping_n_s_per_m:g})"
    )

    start = time.perf_counter()
    truth = make_truth(args.cycles)
    make_s = time.perf_counter() - start
    with tempfile.TemporaryDirectory(prefix="bench_diagnose_") as tmp:
        folder = Path(tmp) / "index_steps"
        start = time.perf_counter()
        count = write_bag(folder, truth)
        write_s = time.perf_counter() - start
        size = sum(f.stat().st_size for f in folder.iterdir())
        print(
            f"input: closed loop + truth replay {make_s:.1f} s; bag of {count} messages on "
            f"7 topics, {size / 1e6:.2f} MB, written in {write_s:.2f} s"
        )
        load_bag_runs(folder)  # imports and decoder generation out of the timing
        load_s, runs = median_time(lambda: load_bag_runs(folder), few)
    run = runs[0]
    period = float(np.median(np.diff(run.time)))
    length_s = run.n_samples * period
    print(
        f"run: {run.name}, {run.n_samples} samples every {period * 1e3:g} ms = {length_s:g} s, "
        f"outputs {', '.join(run.outputs)}, {len(run.setpoints)} setpoints, "
        f"notes: {'; '.join(run.notes) or 'none'}"
    )
    pool = library.applicable(model, frozenset({run.drive}), frozenset(run.outputs))
    print(
        f"library: {len(pool)} applicable of {len(library.ALL)} candidates "
        f"({', '.join(c.name for c in pool)})"
    )

    probe = Probe()
    probe.install()
    data = prepare([run], [])
    data.predict([model])  # numba's cache and the first replay out of the timing
    prepare_s, data = median_time(lambda: prepare([run], []), few)
    replay_s, _ = median_time(lambda: data.predict([model]), more)

    print(
        f"threads: numba {numba.get_num_threads()}, on {cores} cores; load average (1 min) before "
        f"the diagnoses {os.getloadavg()[0]:.1f}"
    )
    diagnose([run], [], model)  # untimed: compile-cache load, first calls
    timings = {
        "as shipped (BLAS on 1 thread during the fits)": time_diagnosis(
            run, model, args.repeat, probe
        )
    }
    # The fits' linear algebra is on 16,000 x 3 matrices, too small to gain from BLAS threads;
    # the comparison shows what two dozen fit threads calling a threaded BLAS would cost.
    limit = fit_module.threadpool_limits
    fit_module.threadpool_limits = lambda **kwargs: contextlib.nullcontext()
    try:
        timings["BLAS threads left at their default"] = time_diagnosis(run, model, 1, probe)
    finally:
        fit_module.threadpool_limits = limit
    threading_layer = numba.threading_layer()

    print()
    print(f"{'':44} {'wall s':>8} {'/ run length':>13} {'run length /':>13}")

    def row(label: str, seconds: float) -> None:
        print(f"{label:44} {seconds:8.3f} {seconds / length_s:13.4f} {length_s / seconds:12.1f}x")

    row(f"load the bag (load_bag_runs, median {few})", load_s)
    row(f"prepare (plans, phases, split, median {few})", prepare_s)
    row(f"starting model's replay (1 set, median {more})", replay_s)
    for label, t in timings.items():
        row(f"diagnosis, full library, {label}", t.wall)
    goal_s = GOAL_S * length_s / GOAL_RUN_S
    for label, t in timings.items():
        total = load_s + t.wall
        print(
            f"{label}: diagnosis wall times {', '.join(f'{w:.1f}' for w in t.walls)} s "
            f"(median of {len(t.walls)}), CPU {t.cpu:.1f} s in the median run "
            f"({t.cpu / t.wall:.2f} cores busy); goal under {goal_s:g} s for "
            f"{length_s:g} s: load + diagnosis {total:.1f} s = {total / goal_s:.2f} x goal "
            f"({'under' if total < goal_s else 'OVER'} the goal)"
        )
    first = next(iter(timings.values())).result
    print(f"verdict: {first.summary_line()}")
    for label, t in list(timings.items())[1:]:
        line = t.result.summary_line()
        print(f"verdict, {label}: " + ("the same" if line == first.summary_line() else line))
    named = "; ".join(
        f"{n['effect']} "
        + ", ".join(f"{k} {p['si_value']:.4g}" for k, p in n['parameters'].items())
        for n in first.named()
    )
    print(
        f"named: {named or 'nothing'} (truth: "
        + ", ".join(f"{k} {v:g}" for k, v in HIDDEN.items())
        + ")"
    )

    for label, t in timings.items():
        fit_s = sum(s for _, s in t.fits)
        threads = max((n for n, _ in t.fits), default=0) * fit_module.STARTS
        print()
        print(
            f"where the time goes, {label} (median run): {t.calls} model evaluations "
            f"(dataset.predict) of {t.sets} parameter sets, {t.sim_sets} distinct physics sets "
            f"simulated in {t.sim_calls} batches"
        )
        print(
            f"  predict {t.predict_s:.1f} s ({t.predict_s / t.wall:.0%} of the wall time), of "
            f"which the batch simulation {t.sim_s:.1f} s: "
            f"{t.sim_sets * length_s / max(t.sim_s, 1e-9):,.0f} simulated unit-s per wall-s at dt "
            f"1 ms, {t.sim_s / max(t.sim_sets, 1) * 1e3:.1f} ms per set (one set alone "
            f"{replay_s * 1e3:.0f} ms)"
        )
        print(
            f"  outside predict (least squares in up to {threads} fit threads at once, waiting, "
            "localise): "
            f"{t.wall - t.predict_s:.1f} s ({(t.wall - t.predict_s) / t.wall:.0%})"
        )
        print(
            f"  fit_structures: {len(t.fits)} calls, {fit_s:.1f} s, {t.rounds} barrier "
            f"rounds; per call " + ", ".join(f"{n} structures {s:.1f} s" for n, s in t.fits)
        )
    print()
    print(
        f"numba threading layer {threading_layer}; load average (1 min) at the end: "
        f"{os.getloadavg()[0]:.1f} on "
        f"{cores} cores (wall times need idle cores)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
