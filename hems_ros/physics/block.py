"""The batch engine: many parameter sets through whole drive series (batch.simulate), in
blocks of sets whose step arithmetic is vectorised across the sets, on the step of kernel.py.

:func:`run_batch` runs blocks of BLOCK sets in parallel (``prange``), each block through time
together, each step in loops over the sets of the block that LLVM vectorises (SIMD):
_block_begin does the start of the step (kernel.begin) and the kinetic solve's first
iteration, _block_iterate the further iterations while any set needs them, _block_finish the
end of the step (kernel.finish) for those sets. They take kernel.step's arithmetic in its
order, so a set gives the same bits in both APIs (without the energy accumulators, the same to
rounding: LLVM may fuse a multiply-add differently). Sets that push or wipe out reversal
points, or need more than BLOCK_ITERATIONS iterations, or turn non-finite, are flagged
(B_REDO) and redone from their old state by kernel.step itself (0.04 % of the steps of the
benchmark's pulse train).

The kernel's functions are called through their module (``kernel.begin``): numba's
dispatchers take their places there when it starts (jit.py).
"""

from __future__ import annotations

import numpy as np
from numba import prange

from hems_ros.physics import kernel, kinetics
from hems_ros.physics.jit import jit, jit_inline, jit_parallel
from hems_ros.physics.rows import (
    N_O,
    N_P,
    N_S,
    P_AS0,
    P_INV_AW,
    P_INV_CA,
    P_INV_CM,
    P_INV_MW,
    P_MF0,
    P_S,
    P_TPX,
    S_DIR,
    S_EJ,
    S_ESHCONV,
    S_MEM,
    S_NREV,
    S_T,
    S_XI,
)

# One float64 buffer holds a block, field f of set j at f * BLOCK + j: the constant offsets
# let LLVM prove that a loop's loads and stores do not overlap.
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
def _solve_iteration(b, j, st, heating, n_points, slope0, it, scaled):
    """One iteration of kernel.step's kinetic solve for set j of block b from ``it`` (a
    kernel.Solve), given the step's start ``st`` (the set's constants and reversal points are
    read from b).

    Returns the updated Solve, 1.0 while the solve goes on and 1.0 if the set has to be redone
    by step.
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
        it.ua,
        it.um,
        heating,
        st.xi,
        st.ua_old,
        st.um_old,
        slope0,
        n_points,
        top,
        b[j + P_MF0 * BLOCK],
        b[j + P_INV_MW * BLOCK],
        b[j + P_AS0 * BLOCK],
        b[j + P_INV_AW * BLOCK],
        scaled,
    )
    r = st.xi + it.d_xi - xi_branch
    if abs(r) <= kernel.XI_TOLERANCE:
        return it, 0.0, closes
    it, settled = kernel.solve_update(st, heating, it, r, dxi_du)
    return it, 0.0 if settled and closes == 0.0 else 1.0, closes


@jit_inline
def _work_flows(b, w):
    return kernel.Flows(
        b[w + W_RES * BLOCK],
        b[w + W_CUR * BLOCK],
        b[w + W_POWER * BLOCK],
        b[w + W_QAIR * BLOCK],
        b[w + W_QSH * BLOCK],
        b[w + W_QSA * BLOCK],
        b[w + W_QHA * BLOCK],
        b[w + W_DTEMP0 * BLOCK],
    )


@jit_inline
def _iteration(b, j, s_in, scaled):
    """_solve_iteration for set j of block b from its work area (W_* fields)."""
    w = B_WORK * BLOCK + j
    c = s_in * BLOCK + j
    it = kernel.Solve(
        b[w + W_DXI * BLOCK],
        b[w + W_LO * BLOCK],
        b[w + W_HI * BLOCK],
        b[w + W_VNEW * BLOCK],
        b[w + W_SIGNEW * BLOCK],
        b[w + W_GAIN * BLOCK],
        b[w + W_UM * BLOCK],
        b[w + W_UA * BLOCK],
    )
    # the work area keeps no elastic trial, which the solve does not read past its start:
    # the start's trial fields hold the solve so far
    st = kernel.Start(
        _work_flows(b, w),
        b[c + S_T * BLOCK],
        b[c + S_XI * BLOCK],
        b[j + P_TPX * BLOCK],
        b[w + W_SF0 * BLOCK],
        b[w + W_SFX * BLOCK],
        b[j + P_S * BLOCK],
        b[w + W_RELAX * BLOCK],
        b[w + W_CIN * BLOCK],
        b[w + W_GIN * BLOCK],
        b[w + W_COUT * BLOCK],
        b[w + W_GOUT * BLOCK],
        b[j + P_INV_CM * BLOCK],
        b[j + P_INV_CA * BLOCK],
        b[w + W_UMOLD * BLOCK],
        b[w + W_UAOLD * BLOCK],
        it.v_new,
        it.sig_new,
        it.sig_gain,
        it.um,
        it.ua,
    )
    heating = b[w + W_HEATING * BLOCK] > 0.0
    n_points = b[w + W_NPOINTS * BLOCK]
    return _solve_iteration(b, j, st, heating, n_points, b[w + W_SLOPE0 * BLOCK], it, scaled)


@jit_inline
def _store_solve(b, j, it, active):
    w = B_WORK * BLOCK + j
    b[w + W_DXI * BLOCK] = it.d_xi
    b[w + W_LO * BLOCK] = it.lo
    b[w + W_HI * BLOCK] = it.hi
    b[w + W_VNEW * BLOCK] = it.v_new
    b[w + W_SIGNEW * BLOCK] = it.sig_new
    b[w + W_GAIN * BLOCK] = it.sig_gain
    b[w + W_UM * BLOCK] = it.um
    b[w + W_UA * BLOCK] = it.ua
    b[w + W_ACTIVE * BLOCK] = active


@jit_inline
def _finish_set(b, j, s_in, s_out, dt, energy):
    """kernel.finish for set j of block b from its W_* fields; True if the new state is finite."""
    w = B_WORK * BLOCK + j
    return kernel.finish(
        b,
        j,
        b,
        s_in * BLOCK + j,
        s_out * BLOCK + j,
        BLOCK,
        b,
        B_OUT * BLOCK + j,
        dt,
        _work_flows(b, w),
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
        st = kernel.begin(b, j, b, sk, BLOCK, drive_kind, b[B_DRIVE * BLOCK + j], dt)
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
        it, active, closes = _solve_iteration(
            b, j, st, heating, n_points, slope0, kernel.solve_start(st, heating), scaled
        )
        redo = moving and (closes > 0.0 or (old_dir != 0.0 and old_dir != direction))
        if moving:
            d_xi, v_new, sig_new = it.d_xi, it.v_new, it.sig_new
        else:
            d_xi, v_new, sig_new, active = 0.0, st.v_new, st.sig_new, 0.0
        if keep:
            solve = kernel.Solve(d_xi, it.lo, it.hi, v_new, sig_new, it.sig_gain, it.um, it.ua)
            _store_solve(b, j, solve, active)
        b[s_out * BLOCK + j + S_DIR * BLOCK] = direction if moving else old_dir
        b[s_out * BLOCK + j + S_NREV * BLOCK] = n_points
        finite = kernel.finish(
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
        it, active, closes = _iteration(b, j, s_in, True)
        if b[w + W_ACTIVE * BLOCK] > 0.0:
            _store_solve(b, j, it, active)
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
            finite = kernel.step(params[i], s, drive_kind, drives[0 if shared else i, k], dt, out)
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
            if not kernel.step(p, s, drive_kind, drives[0 if shared else i, k], dt, out):
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
        run = (params, states, drive_kind, drives, dt, record_every, channels, records, failed_at)
        if 4 * count < BLOCK:
            _run_sets(*run, first, count)
        else:
            _run_block(*run, first, count)
