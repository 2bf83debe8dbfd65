"""The kernel's rows: the packed parameters, the state and the per-step outputs of one unit.

Parameters are packed into a flat float64 row (:func:`pack`, index constants ``P_*``) with
the quantities derived from them precomputed, so that the batch can run many parameter sets
side by side (block.run_batch); the state is a flat row too (``S_*``, :func:`initial_state`),
and each step writes its derived outputs into ``out`` (``O_*``).

Plain Python and numpy, as are the equations pack takes from the blocks (kinetics.band,
loads.referred_load, loads.transmission, friction.capstan_ratio, sheath.sheath_resistances),
which no compiled code calls: a node process builds its rows without numba (jit.py). The
compiled kernel holds these constants as they were when it was compiled (kernel_sources.SOURCES).
"""

from __future__ import annotations

import math

import numpy as np

from hems_ros.physics import friction, kinetics, loads, sheath
from hems_ros.physics.params import UnitParams

# ---------------------------------------------------------------- packed parameters
(
    P_L0,
    P_S,
    P_AREA,
    P_CW,
    P_LAT,
    P_RHO0M,
    P_T0M,
    P_DRDTM,
    P_DRDSM,
    P_RHO0A,
    P_T0A,
    P_DRDTA,
    P_DRDSA,
    P_H0,
    P_H2,
    P_TAMB,
    P_MF0,
    P_INV_MW,
    P_AS0,
    P_INV_AW,
    P_EM,
    P_EA,
    P_ALM,
    P_ALA,
    P_EPSL,
    P_NU,
    P_VSUP,
    P_ILIM,
    P_RSRC,
    P_MN,
    P_BN,
    P_KN,
    P_K3N,
    P_FSTAT,
    P_N,
    P_SHEATH,
    P_GWS,
    P_GSA,
    P_CS,
    P_GHA,
    P_CH,
    P_INV_CH,
    P_HELIX,
    P_A_IN,
    P_F_IN,
    P_A_OUT,
    P_F_OUT,
    P_INV_CW,
    P_INV_CM,
    P_INV_CA,
    P_INV_L0,
    P_INV_CS,
    P_INV_S,
    P_TPX,
    N_P,
) = range(55)

# ---------------------------------------------------------------- state row
STATE_NAMES = (
    "wire_temperature_c",
    "martensite_fraction",
    "stress_pa",
    "slider_position_m",
    "slider_velocity_m_s",
    "sheath_temperature_c",
    "sheath_helix_temperature_c",
    "energy_joule_j",
    "energy_stored_j",
    "energy_convected_j",
    "energy_latent_j",
    "energy_to_sheath_j",
    "energy_sheath_stored_j",
    "energy_sheath_convected_j",
)
(
    S_T,
    S_XI,
    S_SIG,
    S_X,
    S_V,
    S_TS,
    S_TH,
    S_EJ,
    S_ESTORED,
    S_ECONV,
    S_ELAT,
    S_ESH,
    S_ESHSTORED,
    S_ESHCONV,
) = range(len(STATE_NAMES))
N_S = len(STATE_NAMES)
# kinetics memory: last direction (+1 heating, -1 cooling, 0 none yet), number of reversal
# points, then the points (kinetics.memory_branch layout)
S_DIR, S_NREV = N_S, N_S + 1
S_MEM = N_S + 2
N_STATE = S_MEM + kinetics.POINT_SIZE * kinetics.MEMORY_DEPTH

# ---------------------------------------------------------------- per-step outputs
OUT_NAMES = (
    "resistance_ohm",
    "current_a",
    "electrical_power_w",
    "wire_force_n",
    "tendon_force_n",
    "tendon_position_m",
)
O_R, O_I, O_P, O_FW, O_FT, O_XT = range(len(OUT_NAMES))
N_O = len(OUT_NAMES)


def pack(params: UnitParams, temperature_drive: bool = False) -> np.ndarray:
    """Flat float64 row of one parameter set, with the derived quantities precomputed.

    ``temperature_drive``: the row for electrical.DRIVE_TEMPERATURE, whose imposed temperature
    leaves the latent heat nothing to change (P_LAT = P_TPX = 0; see the kernel's docstring).
    """
    w, th, el, ki, co = (
        params.wire,
        params.thermal,
        params.electrical,
        params.kinetics,
        params.constitutive,
    )
    ld = params.load
    p = np.zeros(N_P)
    p[P_L0] = w.length_m
    p[P_S] = w.cross_section_m2
    p[P_AREA] = w.surface_area_m2
    p[P_CW] = params.wire_heat_capacity_j_per_k
    p[P_LAT] = params.wire_latent_heat_j
    p[P_RHO0M], p[P_T0M] = el.rho0_martensite_ohm_m, el.t0_martensite_c
    p[P_DRDTM], p[P_DRDSM] = (
        el.drho_dt_martensite_ohm_m_per_c,
        el.drho_dsigma_martensite_ohm_m_per_pa,
    )
    p[P_RHO0A], p[P_T0A] = el.rho0_austenite_ohm_m, el.t0_austenite_c
    p[P_DRDTA], p[P_DRDSA] = el.drho_dt_austenite_ohm_m_per_c, el.drho_dsigma_austenite_ohm_m_per_pa
    p[P_H0], p[P_H2], p[P_TAMB] = th.h0_w_m2_c, th.h2_w_m2_c3, params.ambient_temperature_c
    p[P_MF0], p[P_INV_MW], p[P_AS0], p[P_INV_AW] = kinetics.band(
        ki.ms0_c, ki.mf0_c, ki.as0_c, ki.af0_c
    )
    p[P_EM], p[P_EA] = co.e_martensite_pa, co.e_austenite_pa
    p[P_ALM], p[P_ALA] = co.alpha_martensite_per_c, co.alpha_austenite_per_c
    p[P_EPSL], p[P_NU] = co.max_recoverable_strain, co.poisson_ratio
    p[P_VSUP], p[P_ILIM] = params.drive.supply_voltage_v, params.drive.current_limit_a
    p[P_RSRC] = params.drive.source_resistance_ohm
    p[P_MN], p[P_BN], p[P_KN], p[P_K3N] = loads.referred_load(
        ld.mass_kg,
        ld.damping_n_s_per_m,
        ld.stiffness_n_per_m,
        ld.pulley_ratio,
        ld.cubic_stiffness_n_per_m3,
    )
    p[P_FSTAT], p[P_N] = ld.static_force_n(), ld.pulley_ratio
    if params.sheath.enabled:
        sh = params.sheath
        r = sheath.sheath_resistances(sh, w.length_m)
        p[P_SHEATH] = 1.0
        p[P_GWS] = 1.0 / r.wire_to_sheath
        p[P_CS] = sh.heat_capacity_j_per_k
        p[P_INV_CS] = 1.0 / p[P_CS]
        # one node: its outer side is the air; two: the helix node, which meets the air.
        # The helix of a one-node sheath stays at ambient (P_INV_CH = 0) and passes nothing on.
        if sh.helix_heat_capacity_j_per_k > 0:
            p[P_HELIX] = 1.0
            p[P_GSA] = 1.0 / sh.liner_helix_resistance_k_per_w
            p[P_GHA] = 1.0 / r.sheath_to_air
            p[P_CH] = sh.helix_heat_capacity_j_per_k
            p[P_INV_CH] = 1.0 / p[P_CH]
        else:
            p[P_GSA] = 1.0 / r.sheath_to_air
    # reciprocals the step would otherwise divide by several times per step
    p[P_INV_CW], p[P_INV_L0], p[P_INV_S] = 1.0 / p[P_CW], 1.0 / w.length_m, 1.0 / w.cross_section_m2
    if temperature_drive:
        p[P_LAT] = 0.0
    p[P_TPX] = (
        p[P_LAT] * p[P_INV_CW]
    )  # temperature rise per unit of martensite formed (eqs. 4.7-4.12)
    p[P_INV_CM], p[P_INV_CA] = 1.0 / ki.cm_pa_per_c, 1.0 / ki.ca_pa_per_c
    cap = params.capstan
    capstan = (
        friction.capstan_ratio(cap.friction_coefficient, cap.bend_angle_rad) if cap.enabled else 1.0
    )
    coulomb = params.glove_friction.force_n if params.glove_friction.enabled else 0.0
    p[P_A_IN], p[P_F_IN], p[P_A_OUT], p[P_F_OUT] = loads.transmission(
        capstan, ld.pulley_ratio, coulomb
    )
    return p


def initial_state(params: UnitParams, temperature_c: float | None = None) -> np.ndarray:
    """Fully martensitic wire at rest in the frictionless static balance with the load.

    Wire and sheath start at the ambient temperature plus ``params.start.temperature_offset_c``
    (a rig still warm from earlier work), or at ``temperature_c`` when given; a wire warmed
    from cold stays martensite only below the stress-free As0 (eq. 4.21), so a start at or
    above it is refused.
    """
    if temperature_c is None:
        start = params.ambient_temperature_c + params.start.temperature_offset_c
    else:
        start = float(temperature_c)
    if not math.isfinite(start) or start >= params.kinetics.as0_c:
        raise ValueError(
            f"start temperature must be finite and below As0 = {params.kinetics.as0_c:g} degC "
            f"(a martensite wire), got {start!r}"
        )
    s = np.zeros(N_STATE)
    s[S_T] = s[S_TS] = s[S_TH] = start
    s[S_XI] = 1.0
    s[S_SIG] = (
        params.load.pulley_ratio * params.load.static_force_n() / params.wire.cross_section_m2
    )
    return s
