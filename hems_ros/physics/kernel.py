"""The one numba step kernel shared by the stepping API (unit.py) and the batch API (batch.py,
through the block engine of block.py).

The kernel steps a unit's state row with its packed parameter row and writes its outputs into
``out`` (the rows and their index constants are in rows.py).

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

The step's start (:func:`begin`) and end (:func:`finish`) are functions of their own, which
the batch (block.run_batch) runs vectorised across the sets of a block; step and the batch
give bit-identical results while the batch keeps the energy accumulators, and agree to
rounding when it skips them. Compilation options (error model, multiply-add contraction) are
in jit.py; numba compiles these functions at their first call (jit.use_numba), and a node
process runs :func:`steps` compiled ahead of time instead (compiled.py).
"""

from __future__ import annotations

import math
from collections import namedtuple

from hems_ros.physics import constitutive, electrical, heat, kinetics, loads, sheath
from hems_ros.physics.jit import jit, jit_inline
from hems_ros.physics.rows import (
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

# The state a step starts from (begin and finish read it where it is).
Before = namedtuple("Before", ("temp", "xi", "sig", "x", "v", "t_sheath", "t_helix"))
# The flows of a step, fixed at its start (the end of the step books them: finish).
Flows = namedtuple("Flows", ("res", "cur", "power", "q_air", "q_sh", "q_sa", "q_ha", "d_temp0"))
# What the kinetic solve and the end of a step take from its start (begin): the flows, the
# start state the solve needs, the coefficients of xi's effect on the temperature and the free
# stress, the load's response, and the elastic trial (v_new ... ua: the solve's first guess).
# Numba keeps a named tuple's fields in registers as it does separate values, so the names cost
# nothing; its classes have to be module globals (block.py builds them as kernel.Flows, ...).
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
# The kinetic solve between its iterations: the martensite increment d_xi, its bracket, and the
# load solve and effective temperatures at d_xi.
Solve = namedtuple("Solve", ("d_xi", "lo", "hi", "v_new", "sig_new", "sig_gain", "um", "ua"))


@jit_inline
def mechanics(sig_free, area, relax, c_in, g_in, c_out, g_out):
    """Implicit wire + load solve for a stress at fixed strain: (v, sigma, dsigma/dsig_free)."""
    v_new, gain = loads.slider_velocity(area * sig_free, c_in, g_in, c_out, g_out)
    return v_new, sig_free - relax * v_new, 1.0 - relax * area * gain


# The step is split into begin (electrical, heat flows, elastic trial), the kinetic solve and
# finish (state update, accumulators, outputs) so that step and the batch's SIMD block path
# (block._step_block) share the arithmetic and give the same results. Both halves address a
# set through (array, offset, stride): field f of the set is a[offset + f * stride]; a packed
# row (pack, initial_state) is offset 0, stride 1, a block of block.BLOCK sets is stride BLOCK.


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
def begin(p, pk, s, sk, n, drive_kind, drive_value, dt):
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
    v_new, sig_new, sig_gain = mechanics(sig_free0, area, relax, c_in, g_in, c_out, g_out)
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
def finish(p, pk, s, sk, dk, n, out, ok, dt, flows, d_xi, v_new, sig_new, energy):
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


@jit_inline
def solve_start(st, heating):
    """The kinetic solve at the elastic trial (d_xi = 0), xi + d_xi bracketed in [0, 1] on the
    side the step's direction allows."""
    lo = -st.xi if heating else 0.0
    hi = 0.0 if heating else 1.0 - st.xi
    return Solve(0.0, lo, hi, st.v_new, st.sig_new, st.sig_gain, st.um, st.ua)


@jit_inline
def solve_update(st, heating, it, r, dxi_du):
    """One iteration of the kinetic solve from ``it``, whose residual is r = xi + d_xi - X(u)
    with the branch's slope dxi_du: the bracket narrowed by r's sign, a Newton step (halving
    the bracket where it leaves it), the load solve and the effective temperatures at the new
    d_xi. Returns the new Solve and True if it took a Newton step that kept the load's
    direction of motion (mechanics' gain unchanged)."""
    lo, hi = (it.lo, it.d_xi) if r > 0.0 else (it.d_xi, it.hi)
    inv_c = st.inv_ca if heating else st.inv_cm
    du_dxi = st.temp_per_xi - it.sig_gain * st.sig_free_per_xi * inv_c
    d_next = it.d_xi - r / (1.0 - dxi_du * du_dxi)
    newton = lo < d_next < hi
    d_xi = d_next if newton else 0.5 * (lo + hi)
    v_new, sig_new, sig_gain = mechanics(
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
    settled = newton and sig_gain == it.sig_gain
    return Solve(d_xi, lo, hi, v_new, sig_new, sig_gain, um, ua), settled


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
    st = begin(p, 0, s, 0, 1, drive_kind, drive_value, dt)
    xi = st.xi
    heating = st.ua > st.ua_old
    cooling = st.um < st.um_old
    if heating and cooling:  # only when C_A != C_M: keep the current direction
        heating = s[S_DIR] > 0.0
    it = solve_start(st, heating)
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
        closed = 0
        for _ in range(MAX_ITERATIONS):
            xi_branch, dxi_du, closed = kinetics.memory_branch(
                it.ua,
                it.um,
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
            r = xi + it.d_xi - xi_branch
            if abs(r) <= XI_TOLERANCE:
                break
            it, settled = solve_update(st, heating, it, r, dxi_du)
            if settled and closed == 0:
                break
        s[S_NREV] = n_points - 2 * closed
    return finish(p, 0, s, 0, 0, 1, out, 0, dt, st.flows, it.d_xi, it.v_new, it.sig_new, True)


@jit
def steps(p, s, drive_kind, drive_value, dt, out, n):
    """``n`` steps of :func:`step` at one drive, in one call (a node integrating a 10 ms
    sample period, the lockstep holding a duty); returns how many ended finite (n if all)."""
    for k in range(n):
        if not step(p, s, drive_kind, drive_value, dt, out):
            return k
    return n
