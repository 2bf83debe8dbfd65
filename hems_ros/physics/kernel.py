"""The one numba step kernel shared by the stepping API (unit.py) and the batch API (batch.py).

The kernel steps a unit's state row with its packed parameter row and writes its outputs into
``out`` (the rows and their index constants are in rows.py); the batch loop runs many
parameter sets in parallel (``prange``).

Order inside one step (dissertation chapter 4): electrical (R, drive) and heat flows at the start
of the step -> elastic trial (no transformation: heat balance, constitutive increment at
fixed strain, implicit wire + load solve) whose effective-temperature change picks heating,
cooling or neither (kinetics.py) -> the martensite increment dxi solved together with its
consequences: dT = ((P - Q) dt + L dxi) / C (eqs. 4.7-4.12, latent heat), the constitutive
increment (eq. 4.26) and the load solve (loads.py) give u_A, u_M at the end of the step, and dxi
must put xi on the kinetics' branch at that u -> sheath node -> energy accumulators.
The coupled update is a scalar root, taken as one Newton step from the elastic trial (a
linearly implicit Euler step, see :func:`step`).

The state row carries, after the named states, the kinetics' reversal-point memory.

A temperature drive (electrical.DRIVE_TEMPERATURE) imposes the wire temperature at the end
of the step instead of the heat balance: no electrical power, and the latent heat changes
nothing, so it runs on a row packed with ``rows.pack(params, temperature_drive=True)``
(P_LAT = P_TPX = 0). The row, not the drive kind, carries this because the batch's block
path reads P_TPX from the packed row in several places; step and the batch then agree.

The batch (run_batch) runs blocks of sets with the step's arithmetic vectorised across the
sets of a block (see "batch" below); step and the batch give bit-identical results while the
batch keeps the energy accumulators, and agree to rounding when it skips them. Compilation
options (error model, multiply-add contraction) are in jit.py; numba compiles these functions
at their first call (jit.use_numba), and a node process runs :func:`steps` compiled ahead of
time instead (compiled.py).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import prange

from hems_ros.physics import constitutive, electrical, heat, kinetics, loads, sheath
from hems_ros.physics.jit import jit, jit_inline, jit_parallel
from hems_ros.physics.rows import (
    N_O,
    N_P,
    N_S,
    O_FT,
    O_FW,
    O_I,
    O_P,
    O_R,
    O_XT,
    P_A_IN,
    P_A_OUT,
    P_ALA,
    P_ALM,
    P_AREA,
    P_AS0,
    P_BN,
    P_CH,
    P_CS,
    P_CW,
    P_DRDSA,
    P_DRDSM,
    P_DRDTA,
    P_DRDTM,
    P_EA,
    P_EM,
    P_EPSL,
    P_F_IN,
    P_F_OUT,
    P_FSTAT,
    P_GHA,
    P_GSA,
    P_GWS,
    P_H0,
    P_H2,
    P_HELIX,
    P_ILIM,
    P_INV_AW,
    P_INV_CA,
    P_INV_CH,
    P_INV_CM,
    P_INV_CS,
    P_INV_CW,
    P_INV_L0,
    P_INV_MW,
    P_INV_S,
    P_K3N,
    P_KN,
    P_L0,
    P_LAT,
    P_MF0,
    P_MN,
    P_N,
    P_NU,
    P_RHO0A,
    P_RHO0M,
    P_RSRC,
    P_S,
    P_SHEATH,
    P_T0A,
    P_T0M,
    P_TAMB,
    P_TPX,
    P_VSUP,
    S_DIR,
    S_ECONV,
    S_EJ,
    S_ELAT,
    S_ESH,
    S_ESHCONV,
    S_ESHSTORED,
    S_ESTORED,
    S_MEM,
    S_NREV,
    S_SIG,
    S_T,
    S_TH,
    S_TS,
    S_V,
    S_X,
    S_XI,
)

# coupled kinetic-mechanical solve: residual tolerance in xi, iteration cap (the bracket
# halves at least every other iteration, so the cap is never the limit in practice)
XI_TOLERANCE = 1e-12
MAX_ITERATIONS = 60

# The state a step starts from (_begin and _finish read it where it is).
Before = namedtuple("Before", ("temp", "xi", "sig", "x", "v", "t_sheath", "t_helix"))
# The flows of a step, fixed at its start (the end of the step books them: _finish).
Flows = namedtuple("Flows", ("res", "cur", "power", "q_air", "q_sh", "q_sa", "q_ha", "d_temp0"))
# What the kinetic solve and the end of a step take from its start (_begin): the flows, the
# start state the solve needs, the coefficients of xi's effect on the temperature and the free
# stress, the load's response, and the elastic trial (v_new ... ua: the solve's first guess).
# Named tuples of floats compile to the same registers as their fields in numba.
Start = namedtuple(
    "Start",
    (
        "flows",
        "temp",
        "xi",
        "temp_per_xi",
        "sig_free0",
        "sig_free_per_xi",
        "area",
        "relax",
        "c_in",
        "g_in",
        "c_out",
        "g_out",
        "inv_cm",
        "inv_ca",
        "um_old",
        "ua_old",
        "v_new",
        "sig_new",
        "sig_gain",
        "um",
        "ua",
    ),
)


@jit_inline
def _mechanics(sig_free, area, relax, c_in, g_in, c_out, g_out):
    """Implicit wire + load solve for a stress at fixed strain: (v, sigma, dsigma/dsig_free)."""
    v_new, gain = loads.slider_velocity(area * sig_free, c_in, g_in, c_out, g_out)
    return v_new, sig_free - relax * v_new, 1.0 - relax * area * gain


# The step is split into _begin (electrical, heat flows, elastic trial), the kinetic solve and
# _finish (state update, accumulators, outputs) so that step and the batch's SIMD block path
# (_step_block) share the arithmetic and give the same results. Both halves address a
# set through (array, offset, stride): field f of the set is a[offset + f * stride]; a packed
# row (pack, initial_state) is offset 0, stride 1, a block of BLOCK sets is stride BLOCK.


@jit_inline
def _before(s, sk, n):
    return Before(
        s[sk + S_T * n],
        s[sk + S_XI * n],
        s[sk + S_SIG * n],
        s[sk + S_X * n],
        s[sk + S_V * n],
        s[sk + S_TS * n],
        s[sk + S_TH * n],
    )


@jit_inline
def _begin(p, pk, s, sk, n, drive_kind, drive_value, dt):
    """Start of a step: drive, heat flows, elastic trial and the kinetic solve's coefficients."""
    temp, xi, sig, x, v, t_sheath, t_helix = _before(s, sk, n)

    rho_m = electrical.phase_resistivity(
        p[pk + P_RHO0M * n], p[pk + P_T0M * n], p[pk + P_DRDTM * n], p[pk + P_DRDSM * n], temp, sig
    )
    rho_a = electrical.phase_resistivity(
        p[pk + P_RHO0A * n], p[pk + P_T0A * n], p[pk + P_DRDTA * n], p[pk + P_DRDSA * n], temp, sig
    )
    res = electrical.wire_resistance(
        electrical.mixture_resistivity(xi, rho_m, rho_a), p[pk + P_L0 * n] - x, p[pk + P_INV_S * n]
    )
    if drive_kind == electrical.DRIVE_DUTY:
        cur, power = electrical.pwm_stage(
            drive_value, res, p[pk + P_VSUP * n], p[pk + P_ILIM * n], p[pk + P_RSRC * n]
        )
    elif drive_kind == electrical.DRIVE_CURRENT:
        cur, power = electrical.current_source(drive_value, res)
    elif drive_kind == electrical.DRIVE_VOLTAGE:
        cur, power = electrical.voltage_source(drive_value, res)
    else:
        cur, power = 0.0, 0.0  # temperature drive: the wire is heated from outside

    t_amb = p[pk + P_TAMB * n]
    # q_sa: out of the (first) sheath node to the helix node, which stays at ambient when
    # there is none (pack); q_ha: helix -> air
    q_sh, q_sa = sheath.sheath_heat_flows(
        temp, t_sheath, t_helix, p[pk + P_GWS * n], p[pk + P_GSA * n]
    )
    q_ha = sheath.helix_heat_loss(t_helix, t_amb, p[pk + P_GHA * n])
    q_air = heat.convection_loss(
        temp, t_amb, p[pk + P_H0 * n], p[pk + P_H2 * n], p[pk + P_AREA * n]
    )
    if p[pk + P_SHEATH * n] > 0.0:
        q_air = 0.0
    else:
        q_sh = 0.0
        q_sa = 0.0
        q_ha = 0.0
    net = power - q_air - q_sh

    # eqs. 4.7-4.12: C dT = (P - Q) dt + L dxi; eq. 4.26 at fixed strain: Omega dxi + Theta dT.
    # A temperature drive imposes dT (its row has P_TPX = 0: pack).
    inv_cw = p[pk + P_INV_CW * n]
    if drive_kind == electrical.DRIVE_TEMPERATURE:
        d_temp0 = drive_value - temp
    else:
        d_temp0 = net * dt * inv_cw
    temp_per_xi = p[pk + P_TPX * n]
    modulus = constitutive.reuss_modulus(xi, p[pk + P_EM * n], p[pk + P_EA * n])
    omega = constitutive.transformation_coefficient(modulus, p[pk + P_EPSL * n])
    theta = constitutive.thermoelastic_coefficient(
        xi, modulus, p[pk + P_ALM * n], p[pk + P_ALA * n], p[pk + P_NU * n]
    )
    sig_free0 = sig + constitutive.stress_increment_at_fixed_strain(omega, theta, 0.0, d_temp0)
    sig_free_per_xi = constitutive.stress_increment_at_fixed_strain(omega, theta, 1.0, temp_per_xi)

    area = p[pk + P_S * n]
    inv_l0 = p[pk + P_INV_L0 * n]
    relax = modulus * dt * inv_l0  # stress drop per slider velocity
    c_in, g_in, c_out, g_out = loads.slider_response(
        area * modulus * inv_l0,
        x,
        v,
        dt,
        p[pk + P_MN * n],
        p[pk + P_BN * n],
        p[pk + P_KN * n],
        p[pk + P_FSTAT * n],
        p[pk + P_A_IN * n],
        p[pk + P_F_IN * n],
        p[pk + P_A_OUT * n],
        p[pk + P_F_OUT * n],
        p[pk + P_K3N * n],
    )

    inv_cm, inv_ca = p[pk + P_INV_CM * n], p[pk + P_INV_CA * n]
    um_old, ua_old = kinetics.effective_temperatures(temp, sig, inv_cm, inv_ca)
    v_new, sig_new, sig_gain = _mechanics(sig_free0, area, relax, c_in, g_in, c_out, g_out)
    um, ua = kinetics.effective_temperatures(temp + d_temp0, sig_new, inv_cm, inv_ca)
    return Start(
        Flows(res, cur, power, q_air, q_sh, q_sa, q_ha, d_temp0),
        temp,
        xi,
        temp_per_xi,
        sig_free0,
        sig_free_per_xi,
        area,
        relax,
        c_in,
        g_in,
        c_out,
        g_out,
        inv_cm,
        inv_ca,
        um_old,
        ua_old,
        v_new,
        sig_new,
        sig_gain,
        um,
        ua,
    )


@jit_inline
def _finish(p, pk, s, sk, dk, n, out, ok, dt, flows, d_xi, v_new, sig_new, energy):
    """End of a step from its start state (read at sk), its ``flows`` and the solve's d_xi,
    v_new and sig_new: new state (written at dk), outputs and, with ``energy``, the energy
    accumulators; True if finite."""
    was = _before(s, sk, n)
    res, cur, power, q_air, q_sh, q_sa, q_ha, d_temp0 = flows
    d_temp = d_temp0 + p[pk + P_TPX * n] * d_xi
    x_new = was.x + v_new * dt
    temp_new = was.temp + d_temp

    s[dk + S_T * n] = temp_new
    s[dk + S_XI * n] = was.xi + d_xi
    s[dk + S_SIG * n] = sig_new
    s[dk + S_X * n] = x_new
    s[dk + S_V * n] = v_new
    d_ts = (q_sh - q_sa) * dt * p[pk + P_INV_CS * n]
    d_th = (q_sa - q_ha) * dt * p[pk + P_INV_CH * n]  # 0 without a helix node
    sheathed = p[pk + P_SHEATH * n] > 0.0
    s[dk + S_TS * n] = was.t_sheath + d_ts if sheathed else was.t_sheath
    s[dk + S_TH * n] = was.t_helix + d_th
    if energy:
        s[dk + S_ESHSTORED * n] = (
            s[sk + S_ESHSTORED * n] + (p[pk + P_CS * n] * d_ts + p[pk + P_CH * n] * d_th)
            if sheathed
            else s[sk + S_ESHSTORED * n]
        )
        s[dk + S_EJ * n] = s[sk + S_EJ * n] + power * dt
        s[dk + S_ESTORED * n] = s[sk + S_ESTORED * n] + p[pk + P_CW * n] * d_temp
        s[dk + S_ECONV * n] = s[sk + S_ECONV * n] + q_air * dt
        s[dk + S_ELAT * n] = s[sk + S_ELAT * n] - p[pk + P_LAT * n] * d_xi
        s[dk + S_ESH * n] = s[sk + S_ESH * n] + q_sh * dt
        s[dk + S_ESHCONV * n] = (
            s[sk + S_ESHCONV * n] + (q_ha if p[pk + P_HELIX * n] > 0.0 else q_sa) * dt
        )

    out[ok + O_R * n] = res
    out[ok + O_I * n] = cur
    out[ok + O_P * n] = power
    out[ok + O_FW * n] = p[pk + P_S * n] * sig_new
    out[ok + O_FT * n] = loads.load_force(
        v_new,
        was.v,
        x_new,
        dt,
        p[pk + P_MN * n],
        p[pk + P_BN * n],
        p[pk + P_KN * n],
        p[pk + P_FSTAT * n],
        p[pk + P_K3N * n],
    )
    out[ok + O_XT * n] = p[pk + P_N * n] * x_new
    return math.isfinite(temp_new) and math.isfinite(sig_new) and math.isfinite(x_new)


@jit
def step(p, s, drive_kind, drive_value, dt, out):
    """Advance one unit by dt in place (state ``s``); write derived outputs to ``out``.

    The martensite increment d solves R(d) = xi + d - X(u(d)) = 0, where u(d) are the
    effective temperatures at the end of the step given d (heat balance with latent heat,
    constitutive increment, load solve) and X the kinetics' branch (kinetics.memory_branch).
    u rises with d and X never rises with u, so R is increasing with slope >= 1 and has one
    root, bracketed by xi + d in [0, 1].

    The step takes one Newton step from the elastic trial (d = 0) and keeps it when it lands
    inside the bracket, the load keeps its direction of motion and no minor loop closes on
    the way: the linearly implicit Euler method, first order like implicit Euler. On an
    outermost branch X is linear in u and u(d) affine, so that step is the root. On a scaled
    branch X is curved and the step leaves a residual of second order in the step's dxi;
    the next step starts from it and its Newton step takes it up, so it does not build up
    (benchmark pulse train: trajectories within 2e-5 of stroke of the converged solve, whose
    extra iterations cost the batch 15 % of its time). Otherwise it iterates to XI_TOLERANCE
    (Newton steps, bisection fallback). Returns False when the new state is not finite.
    """
    st = _begin(p, 0, s, 0, 1, drive_kind, drive_value, dt)
    xi = st.xi
    v_new, sig_new, sig_gain, um, ua = st.v_new, st.sig_new, st.sig_gain, st.um, st.ua
    d_xi = 0.0
    heating = ua > st.ua_old
    cooling = um < st.um_old
    if heating and cooling:  # only when C_A != C_M: keep the current direction
        heating = s[S_DIR] > 0.0
    if heating or cooling:
        direction = 1.0 if heating else -1.0
        memory = s[S_MEM:]
        n_points = int(s[S_NREV])
        mf0, inv_mw, as0, inv_aw = p[P_MF0], p[P_INV_MW], p[P_AS0], p[P_INV_AW]
        if s[S_DIR] != 0.0 and s[S_DIR] != direction:
            n_points = kinetics.push_reversal(
                memory, n_points, st.ua_old, st.um_old, xi, mf0, inv_mw, as0, inv_aw
            )
        s[S_DIR] = direction
        # the printed law's slope at the start, needed only on an outermost branch
        slope0 = (
            kinetics.transformation_slope(
                st.ua_old, st.um_old, xi, heating, mf0, inv_mw, as0, inv_aw
            )
            if n_points < 2
            else 0.0
        )
        inv_c = st.inv_ca if heating else st.inv_cm
        lo = -xi if heating else 0.0
        hi = 0.0 if heating else 1.0 - xi
        closed = 0
        for _ in range(MAX_ITERATIONS):
            xi_branch, dxi_du, closed = kinetics.memory_branch(
                ua,
                um,
                heating,
                memory,
                n_points,
                xi,
                st.ua_old,
                st.um_old,
                slope0,
                mf0,
                inv_mw,
                as0,
                inv_aw,
            )
            r = xi + d_xi - xi_branch
            if abs(r) <= XI_TOLERANCE:
                break
            if r > 0.0:
                hi = d_xi
            else:
                lo = d_xi
            du_dxi = st.temp_per_xi - sig_gain * st.sig_free_per_xi * inv_c
            d_next = d_xi - r / (1.0 - dxi_du * du_dxi)
            newton = lo < d_next < hi
            d_xi = d_next if newton else 0.5 * (lo + hi)
            gain_before = sig_gain
            v_new, sig_new, sig_gain = _mechanics(
                st.sig_free0 + st.sig_free_per_xi * d_xi,
                st.area,
                st.relax,
                st.c_in,
                st.g_in,
                st.c_out,
                st.g_out,
            )
            um, ua = kinetics.effective_temperatures(
                st.temp + st.flows.d_temp0 + st.temp_per_xi * d_xi, sig_new, st.inv_cm, st.inv_ca
            )
            if newton and closed == 0 and sig_gain == gain_before:
                break
        s[S_NREV] = n_points - 2 * closed
    return _finish(p, 0, s, 0, 0, 1, out, 0, dt, st.flows, d_xi, v_new, sig_new, True)


@jit
def steps(p, s, drive_kind, drive_value, dt, out, n):
    """``n`` steps of :func:`step` at one drive, in one call (a node integrating a 10 ms
    sample period, the lockstep holding a duty); returns how many ended finite (n if all)."""
    for k in range(n):
        if not step(p, s, drive_kind, drive_value, dt, out):
            return k
    return n


# ---------------------------------------------------------------- batch
# The batch runs blocks of BLOCK sets through time together, each step in loops over the sets
# of the block that LLVM vectorises (SIMD): _block_begin does the start of the step and the
# kinetic solve's first iteration, _block_iterate the further iterations while any set needs
# them, _block_finish the end of the step for those sets. They take step's arithmetic in step's
# order, so a set gives the same bits in both APIs (without the energy accumulators, the same
# to rounding: LLVM may fuse a multiply-add differently). Sets that push or wipe out reversal
# points, or need more than BLOCK_ITERATIONS iterations, or turn non-finite, are flagged (B_REDO)
# and redone from their old state by step itself (0.04 % of the steps of the benchmark's pulse
# train). One float64 buffer holds the block, field f of set j at f * BLOCK + j: the constant
# offsets let LLVM prove that a loop's loads and stores do not overlap.
BLOCK = 32
BLOCK_ITERATIONS = 8
# top two reversal points (kinetics.memory_branch's r and t: u_A, u_M, xi, z+, z-), a copy of
# the memory the vector loops read (only step changes the memory)
(M_RUA, M_RUM, M_RXI, M_RZP, M_RZM, M_TUA, M_TUM, M_TXI, M_TZP, M_TZM, N_M) = range(11)
# what the iterations and the end of a step need from its start
# (the state at the start of the step and the set's constants are read where they are, in the
# s_in region and in the packed parameters)
(
    W_RES,
    W_CUR,
    W_POWER,
    W_QAIR,
    W_QSH,
    W_QSA,
    W_QHA,
    W_DTEMP0,
    W_SF0,
    W_SFX,
    W_RELAX,
    W_CIN,
    W_GIN,
    W_COUT,
    W_GOUT,
    W_UMOLD,
    W_UAOLD,
    W_HEATING,
    W_NPOINTS,
    W_SLOPE0,
    W_DXI,
    W_LO,
    W_HI,
    W_VNEW,
    W_SIGNEW,
    W_GAIN,
    W_UM,
    W_UA,
    W_ACTIVE,
    N_W,
) = range(30)
# state fields up to the memory (S_T ... S_NREV) in two regions: a step reads one and writes
# the other, the next step the other way round (s_in, s_out below), instead of copying
B_STATE0 = N_P
B_STATE1 = B_STATE0 + S_MEM
B_OUT = B_STATE1 + S_MEM  # outputs of the step
B_DRIVE = B_OUT + N_O  # drive value of the step
B_REDO = B_DRIVE + 1  # 1.0: the set needs step
B_TOP = B_REDO + 1
B_WORK = B_TOP + N_M
B_SIZE = B_WORK + N_W


@jit_inline
def _branch(
    u_a, u_m, heating, xi, ua_old, um_old, slope0, n_points, top, mf0, inv_mw, as0, inv_aw, scaled
):
    """kinetics.memory_branch with at most the top two reversal points ahead (``top``: their
    fields, M_*): (xi, dxi/du, 1.0 if u passed t, i.e. the branch would wipe out a loop).

    ``scaled`` False: no set of the block has two points, which drops the scaled branch from
    the vector loop (every set would evaluate it otherwise).
    """
    if not scaled or n_points < 2.0:
        du = u_a - ua_old if heating else u_m - um_old
        if (du <= 0.0) if heating else (du >= 0.0):
            return xi, 0.0, 0.0
        return xi + slope0 * du, slope0, 0.0
    u = u_a if heating else u_m
    u_s = ua_old if heating else um_old
    u_t = top[M_TUA] if heating else top[M_TUM]
    if (u <= u_s) if heating else (u >= u_s):
        return xi, 0.0, 0.0
    if (u < u_t) if heating else (u > u_t):
        xi_b, dxi = kinetics.scaled_branch(
            u,
            heating,
            top[M_RUA] if heating else top[M_RUM],
            top[M_RXI],
            top[M_RZP] if heating else top[M_RZM],
            u_t,
            top[M_TXI],
            top[M_TZP] if heating else top[M_TZM],
            mf0,
            inv_mw,
            as0,
            inv_aw,
        )
        return xi_b, dxi, 0.0
    return xi, 0.0, 1.0


@jit_inline
def _solve_iteration(
    b,
    j,
    heating,
    xi,
    n_points,
    ua_old,
    um_old,
    slope0,
    temp,
    d_temp0,
    sig_free0,
    sig_free_per_xi,
    relax,
    c_in,
    g_in,
    c_out,
    g_out,
    d_xi,
    lo,
    hi,
    v_new,
    sig_new,
    sig_gain,
    um,
    ua,
    scaled,
):
    """One iteration of step's kinetic solve for set j of block b, from the start-of-step
    values given (the set's constants and reversal points are read from b).

    Returns the updated (d_xi, lo, hi, v_new, sig_new, sig_gain, um, ua), 1.0 while the solve
    goes on and 1.0 if the set has to be redone by step.
    """
    top = (
        b[(B_TOP + M_RUA) * BLOCK + j],
        b[(B_TOP + M_RUM) * BLOCK + j],
        b[(B_TOP + M_RXI) * BLOCK + j],
        b[(B_TOP + M_RZP) * BLOCK + j],
        b[(B_TOP + M_RZM) * BLOCK + j],
        b[(B_TOP + M_TUA) * BLOCK + j],
        b[(B_TOP + M_TUM) * BLOCK + j],
        b[(B_TOP + M_TXI) * BLOCK + j],
        b[(B_TOP + M_TZP) * BLOCK + j],
        b[(B_TOP + M_TZM) * BLOCK + j],
    )
    xi_branch, dxi_du, closes = _branch(
        ua,
        um,
        heating,
        xi,
        ua_old,
        um_old,
        slope0,
        n_points,
        top,
        b[j + P_MF0 * BLOCK],
        b[j + P_INV_MW * BLOCK],
        b[j + P_AS0 * BLOCK],
        b[j + P_INV_AW * BLOCK],
        scaled,
    )
    r = xi + d_xi - xi_branch
    if abs(r) <= XI_TOLERANCE:
        return d_xi, lo, hi, v_new, sig_new, sig_gain, um, ua, 0.0, closes
    if r > 0.0:
        hi = d_xi
    else:
        lo = d_xi
    inv_cm, inv_ca = b[j + P_INV_CM * BLOCK], b[j + P_INV_CA * BLOCK]
    temp_per_xi = b[j + P_TPX * BLOCK]
    du_dxi = temp_per_xi - sig_gain * sig_free_per_xi * (inv_ca if heating else inv_cm)
    d_next = d_xi - r / (1.0 - dxi_du * du_dxi)
    newton = lo < d_next < hi
    d_xi = d_next if newton else 0.5 * (lo + hi)
    gain_before = sig_gain
    v_new, sig_new, sig_gain = _mechanics(
        sig_free0 + sig_free_per_xi * d_xi, b[j + P_S * BLOCK], relax, c_in, g_in, c_out, g_out
    )
    um, ua = kinetics.effective_temperatures(
        temp + d_temp0 + temp_per_xi * d_xi, sig_new, inv_cm, inv_ca
    )
    done = newton and closes == 0.0 and sig_gain == gain_before
    return d_xi, lo, hi, v_new, sig_new, sig_gain, um, ua, 0.0 if done else 1.0, closes


@jit_inline
def _iteration(b, j, s_in, scaled):
    """_solve_iteration for set j of block b from its work area (W_* fields)."""
    w = B_WORK * BLOCK + j
    c = s_in * BLOCK + j
    return _solve_iteration(
        b,
        j,
        b[w + W_HEATING * BLOCK] > 0.0,
        b[c + S_XI * BLOCK],
        b[w + W_NPOINTS * BLOCK],
        b[w + W_UAOLD * BLOCK],
        b[w + W_UMOLD * BLOCK],
        b[w + W_SLOPE0 * BLOCK],
        b[c + S_T * BLOCK],
        b[w + W_DTEMP0 * BLOCK],
        b[w + W_SF0 * BLOCK],
        b[w + W_SFX * BLOCK],
        b[w + W_RELAX * BLOCK],
        b[w + W_CIN * BLOCK],
        b[w + W_GIN * BLOCK],
        b[w + W_COUT * BLOCK],
        b[w + W_GOUT * BLOCK],
        b[w + W_DXI * BLOCK],
        b[w + W_LO * BLOCK],
        b[w + W_HI * BLOCK],
        b[w + W_VNEW * BLOCK],
        b[w + W_SIGNEW * BLOCK],
        b[w + W_GAIN * BLOCK],
        b[w + W_UM * BLOCK],
        b[w + W_UA * BLOCK],
        scaled,
    )


@jit_inline
def _store_solve(b, j, d_xi, lo, hi, v_new, sig_new, sig_gain, um, ua, active):
    w = B_WORK * BLOCK + j
    b[w + W_DXI * BLOCK] = d_xi
    b[w + W_LO * BLOCK] = lo
    b[w + W_HI * BLOCK] = hi
    b[w + W_VNEW * BLOCK] = v_new
    b[w + W_SIGNEW * BLOCK] = sig_new
    b[w + W_GAIN * BLOCK] = sig_gain
    b[w + W_UM * BLOCK] = um
    b[w + W_UA * BLOCK] = ua
    b[w + W_ACTIVE * BLOCK] = active


@jit_inline
def _finish_set(b, j, s_in, s_out, dt, energy):
    """_finish for set j of block b from its W_* fields; True if the new state is finite."""
    w = B_WORK * BLOCK + j
    flows = Flows(
        b[w + W_RES * BLOCK],
        b[w + W_CUR * BLOCK],
        b[w + W_POWER * BLOCK],
        b[w + W_QAIR * BLOCK],
        b[w + W_QSH * BLOCK],
        b[w + W_QSA * BLOCK],
        b[w + W_QHA * BLOCK],
        b[w + W_DTEMP0 * BLOCK],
    )
    return _finish(
        b,
        j,
        b,
        s_in * BLOCK + j,
        s_out * BLOCK + j,
        BLOCK,
        b,
        B_OUT * BLOCK + j,
        dt,
        flows,
        b[w + W_DXI * BLOCK],
        b[w + W_VNEW * BLOCK],
        b[w + W_SIGNEW * BLOCK],
        energy,
    )


@jit_inline
def _block_begin(b, drive_kind, dt, scaled, keep, s_in, s_out, energy):
    """Start of a step and the solve's first iteration for every set of block b; returns how
    many sets need further iterations. Sets that do not are finished here.

    ``keep`` False: the work area is not written, so no set may iterate further (the caller
    runs the step again with ``keep`` when one needs to); most steps need no further
    iteration and save the stores.
    """
    n_active = 0  # an integer count: a float sum is a reduction LLVM may not reorder
    for j in range(BLOCK):
        sk = s_in * BLOCK + j
        w = B_WORK * BLOCK + j
        st = _begin(b, j, b, sk, BLOCK, drive_kind, b[B_DRIVE * BLOCK + j], dt)
        flows = st.flows
        old_dir = b[sk + S_DIR * BLOCK]
        heating = st.ua > st.ua_old
        cooling = st.um < st.um_old
        if heating and cooling:
            heating = old_dir > 0.0
        moving = heating or cooling
        direction = 1.0 if heating else -1.0
        n_points = b[sk + S_NREV * BLOCK]
        slope0 = kinetics.transformation_slope(
            st.ua_old,
            st.um_old,
            st.xi,
            heating,
            b[j + P_MF0 * BLOCK],
            b[j + P_INV_MW * BLOCK],
            b[j + P_AS0 * BLOCK],
            b[j + P_INV_AW * BLOCK],
        )
        if keep:
            b[w + W_RES * BLOCK] = flows.res
            b[w + W_CUR * BLOCK] = flows.cur
            b[w + W_POWER * BLOCK] = flows.power
            b[w + W_QAIR * BLOCK] = flows.q_air
            b[w + W_QSH * BLOCK] = flows.q_sh
            b[w + W_QSA * BLOCK] = flows.q_sa
            b[w + W_QHA * BLOCK] = flows.q_ha
            b[w + W_DTEMP0 * BLOCK] = flows.d_temp0
            b[w + W_SF0 * BLOCK] = st.sig_free0
            b[w + W_SFX * BLOCK] = st.sig_free_per_xi
            b[w + W_RELAX * BLOCK] = st.relax
            b[w + W_CIN * BLOCK] = st.c_in
            b[w + W_GIN * BLOCK] = st.g_in
            b[w + W_COUT * BLOCK] = st.c_out
            b[w + W_GOUT * BLOCK] = st.g_out
            b[w + W_UMOLD * BLOCK] = st.um_old
            b[w + W_UAOLD * BLOCK] = st.ua_old
            b[w + W_HEATING * BLOCK] = 1.0 if heating else 0.0
            b[w + W_NPOINTS * BLOCK] = n_points
            b[w + W_SLOPE0 * BLOCK] = slope0
        lo = -st.xi if heating else 0.0
        hi = 0.0 if heating else 1.0 - st.xi
        d_xi1, lo1, hi1, v1, sig1, gain1, um1, ua1, active, closes = _solve_iteration(
            b,
            j,
            heating,
            st.xi,
            n_points,
            st.ua_old,
            st.um_old,
            slope0,
            st.temp,
            flows.d_temp0,
            st.sig_free0,
            st.sig_free_per_xi,
            st.relax,
            st.c_in,
            st.g_in,
            st.c_out,
            st.g_out,
            0.0,
            lo,
            hi,
            st.v_new,
            st.sig_new,
            st.sig_gain,
            st.um,
            st.ua,
            scaled,
        )
        redo = moving and (closes > 0.0 or (old_dir != 0.0 and old_dir != direction))
        if moving:
            d_xi, v_new, sig_new = d_xi1, v1, sig1
        else:
            d_xi, v_new, sig_new, active = 0.0, st.v_new, st.sig_new, 0.0
        if keep:
            _store_solve(b, j, d_xi, lo1, hi1, v_new, sig_new, gain1, um1, ua1, active)
        b[s_out * BLOCK + j + S_DIR * BLOCK] = direction if moving else old_dir
        b[s_out * BLOCK + j + S_NREV * BLOCK] = n_points
        finite = _finish(
            b,
            j,
            b,
            sk,
            s_out * BLOCK + j,
            BLOCK,
            b,
            B_OUT * BLOCK + j,
            dt,
            flows,
            d_xi,
            v_new,
            sig_new,
            energy,
        )
        b[B_REDO * BLOCK + j] = 1.0 if redo or not finite else 0.0
        n_active += 1 if active > 0.0 else 0
    return n_active


@jit_inline
def _block_iterate(b, s_in):
    """One more iteration of the solve for the sets of block b that need it; how many still do."""
    n_active = 0
    for j in range(BLOCK):
        w = B_WORK * BLOCK + j
        d_xi, lo, hi, v_new, sig_new, sig_gain, um, ua, active, closes = _iteration(
            b, j, s_in, True
        )
        if b[w + W_ACTIVE * BLOCK] > 0.0:
            _store_solve(b, j, d_xi, lo, hi, v_new, sig_new, sig_gain, um, ua, active)
            if closes > 0.0:
                b[B_REDO * BLOCK + j] = 1.0
            n_active += 1 if active > 0.0 else 0
    return n_active


@jit_inline
def _block_finish(b, dt, s_in, s_out, energy):
    """End of the step for every set of block b from its solve; sets still unsolved are flagged."""
    for j in range(BLOCK):
        finite = _finish_set(b, j, s_in, s_out, dt, energy)
        if b[B_WORK * BLOCK + j + W_ACTIVE * BLOCK] > 0.0 or not finite:
            b[B_REDO * BLOCK + j] = 1.0


@jit_inline
def _step_block(b, drive_kind, dt, s_in, s_out, energy):
    """One step of every set of block b from state region s_in into s_out; flags (B_REDO) the sets
    step has to redo and returns how many there are.

    Sets rarely iterate (see step), so the step first runs without the work area, and with
    the scaled branch only when a set of the block has two reversal points; the rerun that
    keeps the work area uses the general form (scaled=True). ``energy`` False skips
    the energy accumulators (about a tenth of a step) when no energy channel is recorded.
    """
    n_scaled = 0
    for j in range(BLOCK):
        n_scaled += 1 if b[(s_in + S_NREV) * BLOCK + j] >= 2.0 else 0
    if n_scaled > 0:
        n_active = _block_begin(b, drive_kind, dt, True, False, s_in, s_out, energy)
    else:
        n_active = _block_begin(b, drive_kind, dt, False, False, s_in, s_out, energy)
    if n_active > 0:  # the same step again, keeping what the iterations need
        n_active = _block_begin(b, drive_kind, dt, True, True, s_in, s_out, energy)
    if n_active > 0:
        for _ in range(BLOCK_ITERATIONS - 1):
            if _block_iterate(b, s_in) == 0:
                break
        _block_finish(b, dt, s_in, s_out, energy)
    n_redo = 0
    for j in range(BLOCK):
        n_redo += 1 if b[B_REDO * BLOCK + j] > 0.0 else 0
    return n_redo


@jit
def _step_block_variant(b, drive_kind, dt, even, energy):
    """_step_block with the state regions and the energy flag as constants in each branch: a
    constant region offset lets LLVM prove that the vector loops' loads and stores do not
    overlap. ``even``: from region 0 into region 1, else back."""
    if energy:
        if even:
            return _step_block(b, drive_kind, dt, B_STATE0, B_STATE1, True)
        return _step_block(b, drive_kind, dt, B_STATE1, B_STATE0, True)
    if even:
        return _step_block(b, drive_kind, dt, B_STATE0, B_STATE1, False)
    return _step_block(b, drive_kind, dt, B_STATE1, B_STATE0, False)


@jit
def _copy_top(b, j, s):
    """The top two reversal points of state row s into block b's copy for set j."""
    n_points = int(s[S_NREV])
    if n_points >= 2:
        r = S_MEM + kinetics.POINT_SIZE * (n_points - 1)
        t = r - kinetics.POINT_SIZE
        for f in range(kinetics.POINT_SIZE):
            b[(B_TOP + f) * BLOCK + j] = s[r + f]
            b[(B_TOP + M_TUA + f) * BLOCK + j] = s[t + f]


@jit
def _run_block(  # noqa: C901 -- one numba loop over a block's steps; its branches are the drives
    params, states, drive_kind, drives, dt, record_every, channels, records, failed_at, first, count
):
    """Sets first .. first + count - 1 of run_batch (count <= BLOCK) through every step."""
    n_steps = drives.shape[1]
    shared = drives.shape[0] == 1
    n_ch = channels.shape[0]
    energy = False
    for c in range(n_ch):
        energy = energy or S_EJ <= channels[c] <= S_ESHCONV
    b = np.zeros(B_SIZE * BLOCK)
    out = np.zeros(N_O)
    for j in range(BLOCK):
        i = first + min(j, count - 1)  # spare lanes repeat the last set and are never read
        for f in range(N_P):
            b[f * BLOCK + j] = params[i, f]
        for f in range(S_MEM):
            b[(B_STATE0 + f) * BLOCK + j] = states[i, f]
        _copy_top(b, j, states[i])
    for j in range(count):
        failed_at[first + j] = -1
    r = 0
    countdown = record_every
    s_in, s_out = B_STATE0, B_STATE1
    for k in range(n_steps):
        if shared:
            for j in range(count):
                b[B_DRIVE * BLOCK + j] = drives[0, k]
        else:
            for j in range(count):
                b[B_DRIVE * BLOCK + j] = drives[first + j, k]
        n_redo = _step_block_variant(b, drive_kind, dt, s_in == B_STATE0, energy)
        for j in range(count if n_redo > 0 else 0):
            i = first + j
            if b[B_REDO * BLOCK + j] == 0.0 or failed_at[i] >= 0:
                continue
            s = states[i]
            for f in range(S_MEM):
                s[f] = b[(s_in + f) * BLOCK + j]
            finite = step(params[i], s, drive_kind, drives[0 if shared else i, k], dt, out)
            for f in range(S_MEM):
                b[(s_out + f) * BLOCK + j] = s[f]
            for f in range(N_O):
                b[(B_OUT + f) * BLOCK + j] = out[f]
            _copy_top(b, j, s)
            if not finite:
                failed_at[i] = k
        countdown -= 1
        if countdown == 0:
            countdown = record_every
            for c in range(n_ch):
                ch = channels[c]
                base = (s_out + ch) * BLOCK if ch < N_S else (B_OUT + ch - N_S) * BLOCK
                for j in range(count):
                    if failed_at[first + j] < 0:
                        records[c, first + j, r] = b[base + j]
            r += 1
        s_in, s_out = s_out, s_in
    for j in range(count):
        if failed_at[first + j] < 0:  # a failed set's row in states keeps its last state
            for f in range(S_MEM):
                states[first + j, f] = b[(s_in + f) * BLOCK + j]


@jit
def _run_sets(
    params, states, drive_kind, drives, dt, record_every, channels, records, failed_at, first, count
):
    """Sets first .. first + count - 1 of run_batch one after the other, through step alone."""
    n_steps = drives.shape[1]
    shared = drives.shape[0] == 1
    n_ch = channels.shape[0]
    out = np.zeros(N_O)
    for i in range(first, first + count):
        s = states[i]
        p = params[i]
        r = 0
        countdown = record_every
        failed_at[i] = -1
        for k in range(n_steps):
            if not step(p, s, drive_kind, drives[0 if shared else i, k], dt, out):
                failed_at[i] = k
                break
            countdown -= 1
            if countdown == 0:
                countdown = record_every
                for c in range(n_ch):
                    ch = channels[c]
                    records[c, i, r] = s[ch] if ch < N_S else out[ch - N_S]
                r += 1


@jit_parallel
def run_batch(params, states, drive_kind, drives, dt, record_every, channels, records, failed_at):
    """Run every set (row of ``params``/``states``) over its row of ``drives``, or over its only
    row when every set has the same input (no copy per set: 256 sets x 30 s at 1 kHz would
    be 61 MB).

    ``channels`` indexes the concatenation (state, outputs); ``records[c, i, r]`` holds
    channel c of set i after step (r + 1) * record_every. ``failed_at[i]`` is the first step whose
    state was not finite (the set stops there), else -1. Blocks of BLOCK sets run in parallel;
    a block of fewer than BLOCK / 4 sets runs set by set (the vector loops would compute all
    BLOCK lanes for them).
    """
    n_sets = params.shape[0]
    n_blocks = (n_sets + BLOCK - 1) // BLOCK
    for blk in prange(n_blocks):
        first = blk * BLOCK
        count = min(BLOCK, n_sets - first)
        if 4 * count < BLOCK:
            _run_sets(
                params,
                states,
                drive_kind,
                drives,
                dt,
                record_every,
                channels,
                records,
                failed_at,
                first,
                count,
            )
        else:
            _run_block(
                params,
                states,
                drive_kind,
                drives,
                dt,
                record_every,
                channels,
                records,
                failed_at,
                first,
                count,
            )
