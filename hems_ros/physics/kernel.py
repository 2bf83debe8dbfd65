"""The one numba step kernel shared by the stepping API (unit.py) and the batch API (batch.py).

Parameters are packed into a flat float64 row (:func:`pack`, index constants ``P_*``) so
the batch loop can run many parameter sets in parallel (``prange``); the state is a flat
row too (``S_*``), and each step writes its derived outputs into ``out`` (``O_*``).

Order inside one step (digest section 3): electrical (R, drive) and heat flows at the start
of the step -> elastic trial (no transformation: heat balance, constitutive increment at
fixed strain, implicit wire + load solve) whose effective-temperature change picks heating,
cooling or neither (kinetics.py) -> the martensite increment dxi solved together with its
consequences: dT = ((P - Q) dt + L dxi) / C (eq. 4.10, latent heat), the constitutive
increment (4.26) and the load solve (loads.py) give u_A, u_M at the end of the step, and dxi
must put xi on the kinetics' branch at that u -> sheath node -> energy accumulators.
The coupled update is a scalar root (safeguarded Newton, see :func:`step`).

The state row carries, after the named states, the kinetics' reversal-point memory.

Numba's on-disk cache only tracks this file, while the kernel inlines the equation
modules; :func:`_invalidate_stale_cache` drops the cached kernel when any of them changed.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

import numpy as np
from numba import njit, prange

from hems_ros.physics import constitutive, electrical, friction, heat, kinetics, loads, sheath
from hems_ros.physics.params import UnitParams


def _invalidate_stale_cache() -> None:
    here = Path(__file__).resolve()
    digest = hashlib.sha256()
    for module in (constitutive, electrical, friction, heat, kinetics, loads, sheath):
        digest.update(Path(module.__file__).read_bytes())
    stamp = here.parent / "__pycache__" / "kernel.deps"
    try:
        if stamp.is_file() and stamp.read_text() == digest.hexdigest():
            return
        for cached in stamp.parent.glob("kernel.*.nb[ic]"):
            cached.unlink()
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(digest.hexdigest())
    except OSError:
        pass  # read-only install: sources cannot change under it either


_invalidate_stale_cache()

# ---------------------------------------------------------------- packed parameters
(P_L0, P_S, P_AREA, P_CW, P_LAT,
 P_RHO0M, P_T0M, P_DRDTM, P_DRDSM, P_RHO0A, P_T0A, P_DRDTA, P_DRDSA,
 P_H0, P_H2, P_TAMB,
 P_MS0, P_MF0, P_AS0, P_AF0,
 P_EM, P_EA, P_ALM, P_ALA, P_EPSL, P_NU,
 P_VSUP, P_ILIM,
 P_MASS, P_DAMP, P_K, P_F0, P_G, P_N,
 P_SHEATH, P_GWS, P_GSA, P_CS,
 P_CAPSTAN, P_COULOMB,
 P_INV_CW, P_INV_CM, P_INV_CA, P_INV_L0, N_P) = range(45)

# ---------------------------------------------------------------- state row
STATE_NAMES = (
    "wire_temperature_c", "martensite_fraction", "stress_pa", "slider_position_m",
    "slider_velocity_m_s", "sheath_temperature_c",
    "energy_joule_j", "energy_stored_j", "energy_convected_j", "energy_latent_j",
    "energy_to_sheath_j", "energy_sheath_stored_j", "energy_sheath_convected_j",
)
(S_T, S_XI, S_SIG, S_X, S_V, S_TS,
 S_EJ, S_ESTORED, S_ECONV, S_ELAT, S_ESH, S_ESHSTORED, S_ESHCONV) = range(len(STATE_NAMES))
N_S = len(STATE_NAMES)
# kinetics memory: last direction (+1 heating, -1 cooling, 0 none yet), number of reversal
# points, then the points (kinetics.memory_branch layout)
S_DIR, S_NREV = N_S, N_S + 1
S_MEM = N_S + 2
N_STATE = S_MEM + kinetics.POINT_SIZE * kinetics.MEMORY_DEPTH

# coupled kinetic-mechanical solve: residual tolerance in xi, iteration cap (the bracket
# halves at least every other iteration, so the cap is never the limit in practice)
XI_TOLERANCE = 1e-12
MAX_ITERATIONS = 60

# ---------------------------------------------------------------- per-step outputs
OUT_NAMES = ("resistance_ohm", "current_a", "electrical_power_w", "wire_force_n",
             "tendon_force_n", "tendon_position_m")
O_R, O_I, O_P, O_FW, O_FT, O_XT = range(len(OUT_NAMES))
N_O = len(OUT_NAMES)


def pack(params: UnitParams) -> np.ndarray:
    """Flat float64 row of one parameter set, with the derived quantities precomputed."""
    w, th, el, ki, co = params.wire, params.thermal, params.electrical, params.kinetics, params.constitutive
    ld = params.load
    p = np.zeros(N_P)
    p[P_L0] = w.length_m
    p[P_S] = w.cross_section_m2
    p[P_AREA] = w.surface_area_m2
    p[P_CW] = th.density_kg_m3 * w.volume_m3 * th.specific_heat_j_kg_c
    p[P_LAT] = th.density_kg_m3 * w.volume_m3 * th.latent_heat_j_kg
    p[P_RHO0M], p[P_T0M] = el.rho0_martensite_ohm_m, el.t0_martensite_c
    p[P_DRDTM], p[P_DRDSM] = el.drho_dt_martensite_ohm_m_per_c, el.drho_dsigma_martensite_ohm_m_per_pa
    p[P_RHO0A], p[P_T0A] = el.rho0_austenite_ohm_m, el.t0_austenite_c
    p[P_DRDTA], p[P_DRDSA] = el.drho_dt_austenite_ohm_m_per_c, el.drho_dsigma_austenite_ohm_m_per_pa
    p[P_H0], p[P_H2], p[P_TAMB] = th.h0_w_m2_c, th.h2_w_m2_c3, params.ambient_temperature_c
    p[P_MS0], p[P_MF0], p[P_AS0], p[P_AF0] = ki.ms0_c, ki.mf0_c, ki.as0_c, ki.af0_c
    p[P_EM], p[P_EA] = co.e_martensite_pa, co.e_austenite_pa
    p[P_ALM], p[P_ALA] = co.alpha_martensite_per_c, co.alpha_austenite_per_c
    p[P_EPSL], p[P_NU] = co.max_recoverable_strain, co.poisson_ratio
    p[P_VSUP], p[P_ILIM] = params.drive.supply_voltage_v, params.drive.current_limit_a
    p[P_MASS], p[P_DAMP], p[P_K] = ld.mass_kg, ld.damping_n_s_per_m, ld.stiffness_n_per_m
    p[P_F0], p[P_G], p[P_N] = ld.pretension_n, ld.gravity_m_s2, ld.pulley_ratio
    if params.sheath.enabled:
        r = sheath.sheath_resistances(params.sheath, w.length_m)
        p[P_SHEATH] = 1.0
        p[P_GWS] = 1.0 / r.wire_to_sheath
        p[P_GSA] = 1.0 / r.sheath_to_air
        p[P_CS] = params.sheath.heat_capacity_j_per_k
    # reciprocals the step would otherwise divide by several times per step
    p[P_INV_CW], p[P_INV_L0] = 1.0 / p[P_CW], 1.0 / w.length_m
    p[P_INV_CM], p[P_INV_CA] = 1.0 / ki.cm_pa_per_c, 1.0 / ki.ca_pa_per_c
    cap = params.capstan
    p[P_CAPSTAN] = friction.capstan_ratio(cap.friction_coefficient, cap.bend_angle_rad) if cap.enabled else 1.0
    p[P_COULOMB] = params.glove_friction.force_n if params.glove_friction.enabled else 0.0
    return p


def initial_state(params: UnitParams) -> np.ndarray:
    """Cold, fully martensitic wire at rest in the frictionless static balance with the load."""
    s = np.zeros(N_STATE)
    s[S_T] = s[S_TS] = params.ambient_temperature_c
    s[S_XI] = 1.0
    s[S_SIG] = params.load.pulley_ratio * params.load.static_force_n() / params.wire.cross_section_m2
    return s


@njit(cache=True)
def _mechanics(sig_free, area, relax, c_in, g_in, c_out, g_out):
    """Implicit wire + load solve for a stress at fixed strain: (v, sigma, dsigma/dsig_free)."""
    v_new, gain = loads.slider_velocity(area * sig_free, c_in, g_in, c_out, g_out)
    return v_new, sig_free - relax * v_new, 1.0 - relax * area * gain


@njit(cache=True)
def step(p, s, drive_kind, drive_value, dt, out):
    """Advance one unit by dt in place (state ``s``); write derived outputs to ``out``.

    The martensite increment d solves R(d) = xi + d - X(u(d)) = 0, where u(d) are the
    effective temperatures at the end of the step given d (heat balance with latent heat,
    constitutive increment, load solve) and X the kinetics' branch (kinetics.memory_branch).
    u rises with d and X never rises with u, so R is increasing with slope >= 1 and has one
    root, bracketed by xi + d in [0, 1] and found by Newton steps that fall back to bisection.
    """
    temp = s[S_T]
    xi = s[S_XI]
    sig = s[S_SIG]
    x = s[S_X]
    v = s[S_V]
    t_sheath = s[S_TS]

    rho_m = electrical.phase_resistivity(p[P_RHO0M], p[P_T0M], p[P_DRDTM], p[P_DRDSM], temp, sig)
    rho_a = electrical.phase_resistivity(p[P_RHO0A], p[P_T0A], p[P_DRDTA], p[P_DRDSA], temp, sig)
    res = electrical.wire_resistance(electrical.mixture_resistivity(xi, rho_m, rho_a), p[P_L0] - x, p[P_S])
    if drive_kind == electrical.DRIVE_DUTY:
        cur, power = electrical.pwm_stage(drive_value, res, p[P_VSUP], p[P_ILIM])
    elif drive_kind == electrical.DRIVE_CURRENT:
        cur, power = electrical.current_source(drive_value, res)
    else:
        cur, power = electrical.voltage_source(drive_value, res)

    if p[P_SHEATH] > 0.0:
        q_air = 0.0
        q_sh, q_sa = sheath.sheath_heat_flows(temp, t_sheath, p[P_TAMB], p[P_GWS], p[P_GSA])
    else:
        q_air = heat.convection_loss(temp, p[P_TAMB], p[P_H0], p[P_H2], p[P_AREA])
        q_sh = 0.0
        q_sa = 0.0
    net = power - q_air - q_sh

    # eq. 4.10: C dT = (P - Q) dt + L dxi; eq. 4.26 at fixed strain: Omega dxi + Theta dT
    d_temp0 = net * dt * p[P_INV_CW]
    temp_per_xi = p[P_LAT] * p[P_INV_CW]
    modulus = constitutive.reuss_modulus(xi, p[P_EM], p[P_EA])
    omega = constitutive.transformation_coefficient(modulus, p[P_EPSL])
    theta = constitutive.thermoelastic_coefficient(xi, modulus, p[P_ALM], p[P_ALA], p[P_NU])
    sig_free0 = sig + constitutive.stress_increment_at_fixed_strain(omega, theta, 0.0, d_temp0)
    sig_free_per_xi = constitutive.stress_increment_at_fixed_strain(omega, theta, 1.0, temp_per_xi)

    area = p[P_S]
    relax = modulus * dt * p[P_INV_L0]                  # stress drop per slider velocity
    c_in, g_in, c_out, g_out = loads.slider_response(
        area * modulus * p[P_INV_L0], x, v, dt, p[P_MASS], p[P_DAMP], p[P_K], p[P_F0], p[P_G], p[P_N],
        p[P_CAPSTAN], p[P_COULOMB])

    inv_cm, inv_ca = p[P_INV_CM], p[P_INV_CA]
    um_old, ua_old = kinetics.effective_temperatures(temp, sig, inv_cm, inv_ca)
    v_new, sig_new, sig_gain = _mechanics(sig_free0, area, relax, c_in, g_in, c_out, g_out)
    um, ua = kinetics.effective_temperatures(temp + d_temp0, sig_new, inv_cm, inv_ca)
    d_xi = 0.0
    heating = ua > ua_old
    cooling = um < um_old
    if heating and cooling:          # only when C_A != C_M: keep the current direction
        heating = s[S_DIR] > 0.0
    if heating or cooling:
        direction = 1.0 if heating else -1.0
        memory = s[S_MEM:]
        n_points = int(s[S_NREV])
        ms0, mf0, as0, af0 = p[P_MS0], p[P_MF0], p[P_AS0], p[P_AF0]
        if s[S_DIR] != 0.0 and s[S_DIR] != direction:
            n_points = kinetics.push_reversal(memory, n_points, ua_old, um_old, xi, ms0, mf0, as0, af0)
        s[S_DIR] = direction
        # the printed law's slope at the start, needed only on an outermost branch
        slope0 = (kinetics.transformation_slope(ua_old, um_old, xi, heating, ms0, mf0, as0, af0)
                  if n_points < 2 else 0.0)
        inv_c = inv_ca if heating else inv_cm
        lo = -xi if heating else 0.0
        hi = 0.0 if heating else 1.0 - xi
        closed = 0
        for _ in range(MAX_ITERATIONS):
            xi_branch, dxi_du, closed = kinetics.memory_branch(
                ua, um, heating, memory, n_points, xi, ua_old, um_old, slope0, ms0, mf0, as0, af0)
            r = xi + d_xi - xi_branch
            if abs(r) <= XI_TOLERANCE:
                break
            if r > 0.0:
                hi = d_xi
            else:
                lo = d_xi
            du_dxi = temp_per_xi - sig_gain * sig_free_per_xi * inv_c
            d_next = d_xi - r / (1.0 - dxi_du * du_dxi)
            newton = lo < d_next < hi
            d_xi = d_next if newton else 0.5 * (lo + hi)
            gain_before = sig_gain
            v_new, sig_new, sig_gain = _mechanics(sig_free0 + sig_free_per_xi * d_xi, area, relax,
                                                  c_in, g_in, c_out, g_out)
            um, ua = kinetics.effective_temperatures(temp + d_temp0 + temp_per_xi * d_xi, sig_new, inv_cm, inv_ca)
            if newton and n_points < 2 and sig_gain == gain_before:
                # outermost branch: X is linear in u and u(dxi) affine while the load keeps its
                # direction of motion, so this Newton step landed on the root
                break
        s[S_NREV] = n_points - 2 * closed
    d_temp = d_temp0 + temp_per_xi * d_xi
    x_new = x + v_new * dt

    s[S_T] = temp + d_temp
    s[S_XI] = xi + d_xi
    s[S_SIG] = sig_new
    s[S_X] = x_new
    s[S_V] = v_new
    if p[P_SHEATH] > 0.0:
        d_ts = (q_sh - q_sa) * dt / p[P_CS]
        s[S_TS] = t_sheath + d_ts
        s[S_ESHSTORED] += p[P_CS] * d_ts
    s[S_EJ] += power * dt
    s[S_ESTORED] += p[P_CW] * d_temp
    s[S_ECONV] += q_air * dt
    s[S_ELAT] -= p[P_LAT] * d_xi
    s[S_ESH] += q_sh * dt
    s[S_ESHCONV] += q_sa * dt

    out[O_R] = res
    out[O_I] = cur
    out[O_P] = power
    out[O_FW] = p[P_S] * sig_new
    out[O_FT] = loads.load_force(v_new, v, x_new, dt, p[P_MASS], p[P_DAMP], p[P_K], p[P_F0],
                                 p[P_G], p[P_N])
    out[O_XT] = p[P_N] * x_new
    return math.isfinite(s[S_T]) and math.isfinite(s[S_SIG]) and math.isfinite(s[S_X])


@njit(cache=True, parallel=True)
def run_batch(params, states, drive_kind, drives, dt, record_every, channels, records, failed_at):
    """Run every set (row of ``params``/``states``/``drives``) over its drive row.

    ``channels`` indexes the concatenation (state, outputs); ``records[c, i, r]`` holds
    channel c of set i after step (r + 1) * record_every. ``failed_at[i]`` is the first step whose
    state was not finite (the set stops there), else -1.
    """
    n_sets, n_steps = drives.shape
    n_ch = channels.shape[0]
    for i in prange(n_sets):
        s = states[i]
        p = params[i]
        out = np.zeros(N_O)
        r = 0
        countdown = record_every
        failed_at[i] = -1
        for k in range(n_steps):
            if not step(p, s, drive_kind, drives[i, k], dt, out):
                failed_at[i] = k
                break
            countdown -= 1
            if countdown == 0:
                countdown = record_every
                for c in range(n_ch):
                    ch = channels[c]
                    records[c, i, r] = s[ch] if ch < N_S else out[ch - N_S]
                r += 1
