"""Physics speed benchmark: the numba kernel against scipy's LSODA on the same equations.

Prints measured numbers and ratios side by side (not a pass/fail test; floors):
- one unit, full model (calibrated sheathed rig), 60 s at 1 kHz: real-time factor (floor 1000x),
  through the batch API (one set) and the stepping API (what a node calls every 1 ms);
- batch, 256 parameter sets x 30 s, recording slider position and wire force (what a fit
  compares): simulated unit-seconds per wall second (floor 1e5), at the 1 kHz step and at the
  100 Hz control period (Ts = 10 ms, dissertation chapter 5), with the trajectory difference between
  the two steps, the CPU time, the threads numba used and the cores they kept busy (fewer
  than the threads: other work on the host had the rest); and at 1 kHz recording every channel
  (mostly the cost of writing 123 MB of records, plus the energy accumulators);
- the same batch on one thread, CPU time per set-step: the SIMD blocks of block.run_batch
  against the sets run one by one through kernel.step, and what each gives on idle cores
  (the wall figures depend on what else the machine runs);
- baseline: scipy.integrate.solve_ivp(method="LSODA") on the same equations (right-hand side
  built from the same equation functions), integrated piecewise between input changes.

Run: python benchmarks/bench_physics.py [--sets N] [--seconds S] [--smoke]
(--smoke: 64 sets x 3 s, which still fill two SIMD blocks, one per thread)
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import numba
import numpy as np
import smoke
from scipy.integrate import solve_ivp

from hems_ros.physics import (
    ActuationUnit,
    block,
    constitutive,
    electrical,
    heat,
    kinetics,
    load_params,
    rows,
    sheath,
    simulate,
)
from hems_ros.physics.batch import CHANNELS
from hems_ros.physics.electrical import DRIVE_NAMES


def current_profile(total_s: float, dt: float) -> np.ndarray:
    """4 A for 2 s every 10 s: full heat/transform/cool cycles."""
    t = np.arange(int(round(total_s / dt))) * dt
    return np.where((t % 10.0) < 2.0, 4.0, 0.0)


def timed_cpu(fn, repeat: int = 3) -> tuple[float, float, float]:
    """(wall, process CPU) seconds of the fastest of ``repeat`` runs, and the median wall time
    (this host's neighbours make single runs vary by tens of per cent)."""
    runs = []
    for _ in range(repeat):
        start, cpu = time.perf_counter(), time.process_time()
        fn()
        runs.append((time.perf_counter() - start, time.process_time() - cpu))
    wall, cpu = min(runs)
    return wall, cpu, float(np.median([w for w, _ in runs]))


def timed(fn, repeat: int = 3) -> float:
    best = math.inf
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def lsoda_rhs(p):
    """Continuous-time form of kernel.step for a hanging-mass rig without friction.

    The printed Duhem law in effective temperature (no reversal-point memory: the profile's
    cycles run the full loop), with dxi/dt = slope du/dt and du/dt = dT/dt - dsigma/dt / C
    solved together as in the kernel.
    """
    c_w, lat, s_area = p[rows.P_CW], p[rows.P_LAT], p[rows.P_S]
    n = p[rows.P_N]

    def rhs(_t, y, cur):
        temp, xi, sig, x, v, ts, th = y
        rho = electrical.mixture_resistivity(
            xi,
            electrical.phase_resistivity(
                p[rows.P_RHO0M], p[rows.P_T0M], p[rows.P_DRDTM], p[rows.P_DRDSM], temp, sig
            ),
            electrical.phase_resistivity(
                p[rows.P_RHO0A], p[rows.P_T0A], p[rows.P_DRDTA], p[rows.P_DRDSA], temp, sig
            ),
        )
        _, power = electrical.current_source(
            cur, electrical.wire_resistance(rho, p[rows.P_L0] - x, p[rows.P_INV_S])
        )
        if p[rows.P_SHEATH] > 0:
            q_sh, q_sa = sheath.sheath_heat_flows(temp, ts, th, p[rows.P_GWS], p[rows.P_GSA])
            q_ha = sheath.helix_heat_loss(th, p[rows.P_TAMB], p[rows.P_GHA])
            net, dts, dth = (
                power - q_sh,
                (q_sh - q_sa) / p[rows.P_CS],
                (q_sa - q_ha) * p[rows.P_INV_CH],
            )
        else:
            net = power - heat.convection_loss(
                temp, p[rows.P_TAMB], p[rows.P_H0], p[rows.P_H2], p[rows.P_AREA]
            )
            dts = dth = 0.0
        e = constitutive.reuss_modulus(xi, p[rows.P_EM], p[rows.P_EA])
        omega = constitutive.transformation_coefficient(e, p[rows.P_EPSL])
        theta = constitutive.thermoelastic_coefficient(
            xi, e, p[rows.P_ALM], p[rows.P_ALA], p[rows.P_NU]
        )
        dtemp0 = net / c_w
        dsig0 = -e * v / p[rows.P_L0] + theta * dtemp0
        u_m, u_a = kinetics.effective_temperatures(temp, sig, p[rows.P_INV_CM], p[rows.P_INV_CA])
        heating = dtemp0 - dsig0 * p[rows.P_INV_CA] > 0
        inv_c = p[rows.P_INV_CA] if heating else p[rows.P_INV_CM]
        slope = kinetics.transformation_slope(
            u_a, u_m, xi, heating, p[rows.P_MF0], p[rows.P_INV_MW], p[rows.P_AS0], p[rows.P_INV_AW]
        )
        du_dxi = lat / c_w - (omega + theta * lat / c_w) * inv_c
        dxi = slope * (dtemp0 - dsig0 * inv_c) / (1.0 - slope * du_dxi)
        dtemp = dtemp0 + lat / c_w * dxi
        dsig = dsig0 + omega * dxi + theta * lat / c_w * dxi
        force = s_area * sig / n
        acc = (force - p[rows.P_FSTAT] - p[rows.P_BN] * v - p[rows.P_KN] * x) / p[rows.P_MN]
        return [dtemp, dxi, dsig, v, acc, dts, dth]

    return rhs


def run_lsoda(params, current: np.ndarray, dt: float) -> np.ndarray:
    """Slider position at the kernel's sample times, integrating between input changes."""
    p = rows.pack(params)
    rhs = lsoda_rhs(p)
    y = rows.initial_state(params)[:7].copy()
    edges = np.flatnonzero(np.diff(current)) + 1
    bounds = np.concatenate([[0], edges, [current.size]])
    out = np.empty(current.size)
    for a, b in zip(bounds[:-1], bounds[1:]):
        t_eval = (np.arange(a, b) + 1) * dt
        sol = solve_ivp(
            rhs,
            (a * dt, b * dt),
            y,
            method="LSODA",
            t_eval=t_eval,
            args=(current[a],),
            rtol=1e-6,
            atol=[1e-6, 1e-8, 1.0, 1e-9, 1e-9, 1e-6, 1e-6],
        )
        out[a:b] = sol.y[3]
        y = sol.y[:, -1]
    return out


def set_by_set(sets, current: np.ndarray, every: int) -> np.ndarray:
    """Slider position and wire force of every set, the sets one after the other through
    kernel.step on one thread (block._run_sets, what run_batch did for every set before the
    SIMD blocks)."""
    packed = np.stack([rows.pack(p) for p in sets])
    states = np.stack([rows.initial_state(p) for p in sets])
    drives = np.ascontiguousarray(np.broadcast_to(current, (len(sets), current.size)))
    channels = np.array([rows.S_X, rows.N_S + rows.O_FW])
    records = np.zeros((2, len(sets), current.size // every))
    failed_at = np.zeros(len(sets), dtype=np.int64)
    block._run_sets(
        packed,
        states,
        DRIVE_NAMES["current"],
        drives,
        1e-3,
        every,
        channels,
        records,
        failed_at,
        0,
        len(sets),
    )
    return records


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", type=int, default=256, help="parameter sets of the batch")
    parser.add_argument(
        "--seconds", type=float, default=30.0, help="simulated time of the batch (one unit: twice)"
    )
    args = smoke.parse_args(parser, sets=64, seconds=3.0)
    n_sets, span = args.sets, args.seconds
    params = load_params("sheathed_calibrated")
    dt = 1e-3
    print(
        "physics benchmark (calibrated sheathed rig: 30 N mass + 20 N spring, 4 A x 2 s every 10 s)"
    )
    cur_unit = current_profile(2 * span, dt)
    simulate(params, dt, current=cur_unit[:10])  # compile / load the cache

    t_batch1 = timed(lambda: simulate(params, dt, current=cur_unit, channels=["slider_position_m"]))
    unit = ActuationUnit(params, dt)

    def stepping():
        unit.reset()
        for c in cur_unit:
            unit.step(current=c)

    t_step = timed(stepping, repeat=1)
    print(
        f"one unit, {2 * span:g} s at 1 kHz, batch API : {t_batch1 * 1e3:8.1f} ms  real-time "
        f"factor {2 * span / t_batch1:9.0f}x (floor 1000x: {2 * span / t_batch1 / 1000:.1f} x "
        f"floor)"
    )
    print(
        f"one unit, {2 * span:g} s at 1 kHz, step API  : {t_step * 1e3:8.1f} ms  real-time "
        f"factor {2 * span / t_step:9.0f}x (a node needs 1x)"
    )

    cur_span = current_profile(span, dt)
    lsoda_s = timed(lambda: run_lsoda(params, cur_span, dt), repeat=1)
    x_lsoda = run_lsoda(params, cur_span, dt)
    x_kernel = simulate(params, dt, current=cur_span).slider_position_m[0]
    diff = np.max(np.abs(x_lsoda - x_kernel)) / np.ptp(x_kernel)
    print(
        f"LSODA baseline, one unit {span:g} s      : {lsoda_s * 1e3:8.1f} ms  real-time factor "
        f"{span / lsoda_s:9.1f}x; kernel / LSODA speed {lsoda_s / (t_batch1 / 2):.0f}x; max "
        f"|x_kernel - x_LSODA| = {diff:.2%} of stroke"
    )

    sets = [
        params.replace({"sheath.liner_helix_resistance_k_per_w": r})
        for r in np.linspace(1.0, 4.0, n_sets)
    ]
    threads = numba.get_num_threads()
    for step in (1e-3, 1e-2):
        cur = current_profile(span, step)
        every = max(1, int(round(0.01 / step)))
        simulate(sets, step, current=cur[:10])
        t, cpu, t_median = timed_cpu(
            lambda step=step, cur=cur, every=every: simulate(
                sets,
                step,
                current=cur,
                record_every=every,
                channels=["slider_position_m", "wire_force_n"],
            ),
            repeat=7,
        )
        rate = n_sets * span / t
        print(
            f"batch {n_sets} sets x {span:g} s, dt {step * 1e3:4.0f} ms : {t * 1e3:8.1f} ms  "
            f"{rate:10.0f} unit-s per wall-s (floor 1e5: {rate / 1e5:.2f} x floor; fastest of 7, "
            f"median {n_sets * span / t_median / 1e5:.2f} x floor; LSODA at this rate: "
            f"{span / lsoda_s:.1f}, ratio {rate / (span / lsoda_s):.0f}x); CPU {cpu * 1e3:.0f} ms "
            f"on {threads} threads ({numba.threading_layer()}), {cpu / t:.2f} of {threads} cores "
            f"busy, {cpu / (n_sets * cur.size) * 1e9:.1f} ns per set-step"
        )

    cur = current_profile(span, 1e-3)
    t_all, _, _ = timed_cpu(lambda: simulate(sets, 1e-3, current=cur, record_every=10), repeat=5)
    mb = len(CHANNELS) * n_sets * (cur.size // 10) * 8 / 1e6
    print(
        f"the same at dt 1 ms recording every channel ({len(CHANNELS)} channels, {mb:.0f} MB of "
        f"records, energy accumulators on): {n_sets * span / t_all:10.0f} unit-s per wall-s "
        f"({n_sets * span / t_all / 1e5:.2f} x floor, fastest of 5)"
    )

    # Per-thread cost, one thread (CPU time: robust to other load on the machine): the SIMD
    # blocks against the same sets run one by one through kernel.step (the batch before blocks)
    cur = current_profile(span, 1e-3)
    numba.set_num_threads(1)
    _, cpu_blocks, _ = timed_cpu(
        lambda: simulate(
            sets, 1e-3, current=cur, record_every=10, channels=["slider_position_m", "wire_force_n"]
        ),
        repeat=7,
    )
    numba.set_num_threads(threads)
    _, cpu_sets, _ = timed_cpu(lambda: set_by_set(sets, cur, 10), repeat=1)
    per_step = {
        name: c / (n_sets * cur.size) for name, c in (("blocks", cpu_blocks), ("sets", cpu_sets))
    }
    cores = os.cpu_count() or 1
    print(
        f"one thread, dt 1 ms, ns per set-step: SIMD blocks {per_step['blocks'] * 1e9:.1f}, set by "
        f"set {per_step['sets'] * 1e9:.1f} (ratio {per_step['sets'] / per_step['blocks']:.1f}x); "
        f"on {cores} idle cores that is {cores * 1e-3 / per_step['blocks']:.0f} vs "
        f"{cores * 1e-3 / per_step['sets']:.0f} unit-s per wall-s (floor 1e5: "
        f"{cores * 1e-3 / per_step['blocks'] / 1e5:.2f} x floor)"
    )
    load = os.getloadavg()[0]
    print(
        f"load average (1 min) at the end: {load:.1f} on {cores} cores; wall figures need idle "
        f"cores, the one-thread CPU figures much less so"
    )
    fine = simulate(params, 1e-3, current=cur_span, record_every=10).slider_position_m[0]
    coarse = simulate(params, 1e-2, current=current_profile(span, 1e-2)).slider_position_m[0]
    print(
        f"dt 10 ms vs 1 ms trajectory difference: "
        f"{np.max(np.abs(fine - coarse)) / np.ptp(fine):.2%} of stroke"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
