"""Load block (eqs. 4.32-4.35) with the HEMS pulley multiplier.

The slider position x is the wire's contraction (positive when the wire shortens), so the
wire strain changes by deps = -dx / L. The load sits behind a pulley of ratio n (tendon
displacement n x, tendon force F_wire / n before losses) and obeys, in load coordinates,

    m x_L'' = F_L - m g - b x_L' - F_0 - k x_L - k3 x_L^3.        (4.33, 4.34)

The cubic term (a stiffening spring, params.Load) is beyond the dissertation's loads.

One implicit (backward-Euler) step solves the wire and the load together: the wire force
at the end of the step is F_w = W0 - K dt v with W0 = S (sigma + Omega dxi + Theta dT) and
K = S E / L, so v follows from one linear equation. With m = 0 (springs) the same equation
is the algebraic force balance F_w = F_load, solved consistently instead of integrated;
with a hanging mass it is unconditionally stable (the wire-mass resonance is ~46 rad/s,
0.05 rad per 1 ms step). The cubic term enters linearised about the start of the step
(a linearly implicit step), which keeps v linear in W0; at rest the balance is exact.
"""

from __future__ import annotations

from hems_ros.physics.friction import transmitted_force
from hems_ros.physics.jit import jit


def transmission(
    capstan: float, pulley: float, coulomb: float
) -> tuple[float, float, float, float]:
    """(a_in, f_in, a_out, f_out): the load receives F_L = a F_wire + f while the slider moves
    in / out (friction.transmitted_force), constants of a parameter set (rows.pack)."""
    return (
        transmitted_force(1.0, 1.0, capstan, pulley, 0.0),
        transmitted_force(0.0, 1.0, capstan, pulley, coulomb),
        transmitted_force(1.0, -1.0, capstan, pulley, 0.0),
        transmitted_force(0.0, -1.0, capstan, pulley, coulomb),
    )


def referred_load(
    mass: float, damping: float, stiffness: float, pulley: float, cubic_stiffness: float = 0.0
) -> tuple[float, float, float, float]:
    """The load's coefficients in eq. 4.33 written for the slider (x_L = n x):
    (m n, b n, k n, k3 n^3), so that m n x'' = F_L - F_static - b n x' - k n x - k3 n^3 x^3
    with F_static = m g + F_0 (params.Load.static_force_n): forces stay in load coordinates.
    Constants of a parameter set (rows.pack), so a step does not multiply them again."""
    return (
        mass * pulley,
        damping * pulley,
        stiffness * pulley,
        cubic_stiffness * (pulley * pulley * pulley),
    )


@jit
def slider_response(
    wire_stiffness,
    x,
    v,
    dt,
    mass_n,
    damping_n,
    stiffness_n,
    static_force,
    a_in,
    f_in,
    a_out,
    f_out,
    cubic_n=0.0,
):
    """Slider velocity at the end of the step as v = c + g W0, per direction of motion.

    Returns (c_in, g_in, c_out, g_out) for motion inward and outward (eqs. 4.32-4.35 with the
    :func:`transmission` coefficients). They depend on the state at the start of the step
    only, so the kernel computes them once and evaluates :func:`slider_velocity` for each W0
    its kinetic-mechanical solve tries. The load comes as :func:`referred_load` gives it, with
    the static force m g + F_0. The cubic spring term k3 x^3 is linearised about the start
    position, k3 x_new^3 ~ k3 x^3 + 3 k3 x^2 v dt, so that v stays linear in W0.
    """
    inv_dt = 1.0 / dt  # one division per batch loop (dt is the same for every set)
    cubic_x2 = cubic_n * x * x
    inertia = mass_n * inv_dt + damping_n + (stiffness_n + 3.0 * cubic_x2) * dt
    rest = mass_n * v * inv_dt - static_force - stiffness_n * x - cubic_x2 * x
    # F_L(dir) = a_dir * (w0 - K dt v) + f_dir, linear in v
    den_in = inertia + a_in * wire_stiffness * dt
    den_out = inertia + a_out * wire_stiffness * dt
    inv_both = 1.0 / (den_in * den_out)  # one division for both directions
    inv_den_in = den_out * inv_both
    inv_den_out = den_in * inv_both
    return (
        (rest + f_in) * inv_den_in,
        a_in * inv_den_in,
        (rest + f_out) * inv_den_out,
        a_out * inv_den_out,
    )


@jit
def slider_velocity(w0, c_in, g_in, c_out, g_out):
    """Slider velocity at the end of the step and dv/dW0 (coefficients from slider_response).

    Tries motion inward, then outward, else the slider sticks (v = 0): the direction whose
    solution has a consistent sign is the unique implicit-Euler solution with friction.
    """
    v_in = c_in + g_in * w0
    if v_in > 0.0:
        return v_in, g_in
    v_out = c_out + g_out * w0
    if v_out < 0.0:
        return v_out, g_out
    return 0.0, 0.0


@jit
def load_force(v_new, v_old, x_new, dt, mass_n, damping_n, stiffness_n, static_force, cubic_n=0.0):
    """Force the load receives (load coordinates), from its own equation of motion (eq. 4.33),
    with the load as :func:`referred_load` gives it and the static force m g + F_0.

    The cubic term is the exact law at the end of the step: the step solved it linearised
    (:func:`slider_response`), so with k3 > 0 this force and the transmitted wire force differ
    by k3 (3 x dx^2 + dx^3), second order in the step's dx and 0 at rest.
    """
    return (
        mass_n * (v_new - v_old) * (1.0 / dt)
        + static_force
        + damping_n * v_new
        + stiffness_n * x_new
        + cubic_n * x_new * x_new * x_new
    )
