"""Phase kinetics block (digest section 3, eqs. 4.13-4.25): Duhem model, Likhachev scaling.

Major branches z+(T) (heating) and z-(T) (cooling) are tanh curves between the
stress-shifted transformation temperatures. Inside the hysteresis band the state moves
with the active branch's slope scaled by its relative position between the branches,
which produces minor loops. The active branch is chosen from the sign of dT/dt, so the
kernel computes the heat balance first (heat.temperature_increment).
"""

from __future__ import annotations

import math

from numba import njit

# tanh(a) rounds to exactly +-1 in double precision beyond |a| = 19.06; skipping the call
# there is exact and saves most of the kernel's time outside the transformation bands.
TANH_SATURATION = 19.5

# Below this branch separation both branches coincide (far outside the loop) and the
# scaling ratio is 0/0; the branch slope is then ~0 too, so any ratio in [0, 1] is exact.
BRANCH_GAP_FLOOR = 1e-12


@njit(cache=True)
def transformation_temperatures(stress_pa, ms0, mf0, as0, af0, cm, ca):
    """Stress-shifted temperatures, eq. 4.25: Ms = Ms0 + sigma/C_M ... Af = Af0 + sigma/C_A."""
    shift_m = stress_pa / cm
    shift_a = stress_pa / ca
    return ms0 + shift_m, mf0 + shift_m, as0 + shift_a, af0 + shift_a


@njit(cache=True)
def _tanh(a):
    if a > TANH_SATURATION:
        return 1.0
    if a < -TANH_SATURATION:
        return -1.0
    return math.tanh(a)


@njit(cache=True)
def heating_branch(temperature_c, a_s, a_f):
    """z+(T) = 1/2 tanh[2((As - T)/(Af - As) + 1/2)] + 1/2 and dz+/dT (eqs. 4.17, 4.20)."""
    th = _tanh(2.0 * ((a_s - temperature_c) / (a_f - a_s) + 0.5))
    return 0.5 * th + 0.5, -(1.0 - th * th) / (a_f - a_s)


@njit(cache=True)
def cooling_branch(temperature_c, m_s, m_f):
    """z-(T) = 1/2 tanh[2((Mf - T)/(Ms - Mf) + 1/2)] + 1/2 and dz-/dT (eqs. 4.18, 4.21)."""
    th = _tanh(2.0 * ((m_f - temperature_c) / (m_s - m_f) + 0.5))
    return 0.5 * th + 0.5, -(1.0 - th * th) / (m_s - m_f)


@njit(cache=True)
def transformation_slope(temperature_c, xi, heating, m_s, m_f, a_s, a_f):
    """dxi/dT on the active branch (eqs. 4.22-4.24); dxi/dt = slope * dT/dt.

    Heating: dz+/dT (xi - z-)/(z+ - z-); cooling: dz-/dT (z+ - xi)/(z+ - z-).
    The ratio is the state's relative position inside the band. It is kept >= 0 so that a
    state pushed outside the band (stress shifts the branches, O(dT^2) step error) never
    transforms backwards (heating never forms martensite); above 1 it is left as printed,
    which pulls a state outside the band back onto the active branch.
    """
    zp, dzp = heating_branch(temperature_c, a_s, a_f)
    zm, dzm = cooling_branch(temperature_c, m_s, m_f)
    gap = zp - zm
    if heating:
        ratio = (xi - zm) / gap if gap > BRANCH_GAP_FLOOR else 1.0
        slope = dzp
    else:
        ratio = (zp - xi) / gap if gap > BRANCH_GAP_FLOOR else 1.0
        slope = dzm
    if ratio < 0.0:
        ratio = 0.0
    return slope * ratio
