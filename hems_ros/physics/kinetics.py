"""Phase kinetics block (eqs. 4.13-4.25): Duhem model, Likhachev scaling,
with return-point memory.

Effective temperature (eq. 4.25). Stress shifts the transformation temperatures by
sigma/C, so a branch evaluated at T with shifted temperatures equals the same branch at the
effective temperature with the zero-stress temperatures: the heating branch z+ (eq. 4.21)
is a function of u_A = T - sigma/C_A, the cooling branch z- (eq. 4.23) of
u_M = T - sigma/C_M. The kinetics are written in u: the increments of eqs. 4.22-4.24 are
dxi = dz/du * ratio * du, with du = dT - dsigma/C. A stiffening bias spring (stress rising
as the wire contracts) then moves the state along its branch instead of off it, which is
what lets return points be reached at all under the 12 N spring. Heating means u_A rises,
cooling means u_M falls; the kernel finds both from an elastic trial of the step and then
solves the kinetic and mechanical updates of the step together (kernel.step).

Return-point memory (beyond the printed law). Eqs. 4.22-4.24 are a first-order Duhem law:
their state is (u, xi) only, so re-heating from inside the band follows a curve that
passes the previous reversal 0.045 away from it in xi (six-pulse scenario, Table 4.1),
while the dissertation's Fig. 4.6 shows closing minor loops. The kinetics therefore keep a
stack of reversal points (u_A, u_M, xi) and follow Madelung's rules, as in Preisach models:

- a reversal of u pushes the current point;
- a branch with no earlier reversal ahead of it (the outermost branches, and the first
  heating from the martensitic start) is the printed law, eqs. 4.22-4.24;
- a branch that starts at reversal point r with the earlier reversal point t ahead of it
  (the top two of the stack) is the active major branch (4.21 or 4.23) scaled through both
  points, xi = xi_t + (xi_r - xi_t) (z(u) - z(u_t)) / (z(u_r) - z(u_t)), so it reaches t
  exactly;
- reaching t closes the minor loop: r and t are wiped out and the state continues on the
  branch it followed before it reversed at t.

The stack holds MEMORY_DEPTH points; a reversal beyond that forgets the innermost loop
(the top two points), which keeps the nesting order valid.
"""

from __future__ import annotations

import math

from hems_ros.physics.jit import intrinsic, jit, jit_inline

# Below this branch separation both branches coincide (far outside the loop) and the
# scaling ratio is 0/0; the branch slope is then ~0 too, so any ratio in [0, 1] is exact.
BRANCH_GAP_FLOOR = 1e-12

# Reversal points kept. Nested minor loops of a pulse series or a position controller use
# a few; the depth only bounds memory for long noisy inputs. Each point holds u_A, u_M, xi
# and the branch values z+(u_A), z-(u_M), which every step on a scaled branch needs.
MEMORY_DEPTH = 16
POINT_SIZE = 5


@jit
def effective_temperatures(temperature_c, stress_pa, inv_cm, inv_ca):
    """(u_M, u_A) = (T - sigma/C_M, T - sigma/C_A): eq. 4.25 moved onto the temperature.

    Takes 1/C_M and 1/C_A (the kernel keeps the reciprocals per parameter set).
    """
    return temperature_c - stress_pa * inv_cm, temperature_c - stress_pa * inv_ca


# e^x = 2^k e^r, x = k ln 2 + r, |r| <= ln(2)/2: Cody-Waite split of ln 2 (k ln2_hi is exact
# for |k| < 2^21), k rounded to nearest by adding 1.5 * 2^52, e^r by a polynomial of degree 11
# in Estrin's scheme (a dependency chain of 4 multiply-adds instead of Horner's 11, which made
# the scalar step latency-bound), 2^k built in the exponent bits. Within 1 ulp of libm's exp.
_LN2_HI = 6.93147180369123816490e-01
_LN2_LO = 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e00
_ROUND = 6755399441055744.0
_EXP_FLOOR = -708.0
# (e^r - 1 - r) / r^2 interpolated at 10 Chebyshev nodes of [-ln(2)/2, ln(2)/2] (computed in
# 50-digit arithmetic): 1.7e-17 from e^r there, as good as the Taylor series to r^13 with two
# terms fewer
(_C2, _C3, _C4, _C5, _C6, _C7, _C8, _C9, _C10, _C11) = (
    0.5000000000000001,
    0.16666666666666669,
    0.041666666666624164,
    0.008333333333330065,
    0.0013888888917196719,
    0.00019841269863040545,
    2.4801521322368692e-05,
    2.7557268480310024e-06,
    2.7620075879983367e-07,
    2.5100375832561234e-08,
)


@intrinsic
def _float_bits(typingctx, x):
    """The IEEE-754 bits of a float64 as an int64 (a register reinterpretation)."""
    from llvmlite import ir
    from numba import types

    if not isinstance(x, types.Float):
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return types.int64(types.float64), codegen


@intrinsic
def _bits_float(typingctx, bits):
    """The float64 whose IEEE-754 bits are the int64 ``bits``."""
    from llvmlite import ir
    from numba import types

    if not isinstance(bits, types.Integer):
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(types.int64), codegen


@jit_inline
def exp_nonpositive(x):
    """e^x for x <= 0, in plain arithmetic (within about 1 ulp of libm's exp).

    The libm call is opaque to LLVM's loop vectoriser; this is not, so the batch can run the
    branch functions for several parameter sets per instruction (block.run_batch). Below
    -708 it returns 0 where libm returns a subnormal number or 0 (2^k stays a normal number
    in the arithmetic); z and 1 - z of :func:`_logistic` are then exactly 0 and 1 as before.
    """
    xc = max(x, _EXP_FLOOR)
    t = xc * _INV_LN2 + _ROUND
    kf = t - _ROUND
    r = (xc - kf * _LN2_HI) - kf * _LN2_LO
    r2 = r * r
    r4 = r2 * r2
    tail = (
        ((_C2 + _C3 * r) + (_C4 + _C5 * r) * r2)
        + ((_C6 + _C7 * r) + (_C8 + _C9 * r) * r2) * r4
        + (_C10 + _C11 * r) * (r4 * r4)
    )
    poly = 1.0 + (r + r2 * tail)  # the leading 1 + r added last keeps the rounding near 1/2 ulp
    k = _float_bits(t) - _float_bits(_ROUND)
    return poly * _bits_float((k + 1023) << 52) if x >= _EXP_FLOOR else 0.0


@jit_inline
def _logistic(a):
    """(1/2 tanh(a) + 1/2, 1 - tanh(a)^2) through one exp: 1/2 tanh(a) + 1/2 = 1/(1 + e^(-2a)).

    The exponent is taken <= 0 on either side, so it never overflows, and z and 1 - z both
    come without cancellation. One exp is cheaper than tanh, the kernel's largest cost.
    """
    e = exp_nonpositive(-2.0 * abs(a))
    d = 1.0 / (1.0 + e)
    z = d if a >= 0.0 else e * d
    rest = e * d if a >= 0.0 else d
    return z, 4.0 * z * rest


def band(m_s: float, m_f: float, a_s: float, a_f: float) -> tuple[float, float, float, float]:
    """The transformation band as the kinetics take it: (Mf, 1/(Ms - Mf), As, 1/(Af - As)).

    The reciprocal widths are constants of a parameter set; the batch would otherwise divide
    by each width in every step of every set (rows.pack keeps them).
    """
    return m_f, 1.0 / (m_s - m_f), a_s, 1.0 / (a_f - a_s)


@jit_inline
def _tanh_branch(temperature_c, start_c, inv_width):
    """z = 1/2 tanh[2((start - T) inv_width + 1/2)] + 1/2 and dz/dT: both branches' form."""
    z, sech2 = _logistic(2.0 * ((start_c - temperature_c) * inv_width + 0.5))
    return z, -sech2 * inv_width


@jit_inline
def heating_branch(temperature_c, a_s, inv_width):
    """z+(T) = 1/2 tanh[2((As - T)/(Af - As) + 1/2)] + 1/2 and dz+/dT (eq. 4.21 and its derivative);
    ``inv_width`` = 1/(Af - As)."""
    return _tanh_branch(temperature_c, a_s, inv_width)


def heating_branch_temperature(transformed_fraction: float, a_s: float, a_f: float) -> float:
    """Temperature at which the major heating branch (eq. 4.21) has turned ``transformed_fraction``
    of the martensite to austenite: z+(T) = 1 - f solved for T, T = As + (Af - As)(1/2 -
    atanh(1 - 2 f)/2).

    Pass the stress-shifted As, Af (eq. 4.25) for a loaded wire.
    """
    if not 0.0 < transformed_fraction < 1.0:
        raise ValueError(f"transformed_fraction must be in (0, 1), got {transformed_fraction!r}")
    return a_s + (a_f - a_s) * (0.5 - math.atanh(1.0 - 2.0 * transformed_fraction) / 2.0)


@jit_inline
def cooling_branch(temperature_c, m_f, inv_width):
    """z-(T) = 1/2 tanh[2((Mf - T)/(Ms - Mf) + 1/2)] + 1/2 and dz-/dT (eq. 4.23 and its derivative);
    ``inv_width`` = 1/(Ms - Mf)."""
    return _tanh_branch(temperature_c, m_f, inv_width)


@jit_inline
def transformation_slope(u_a, u_m, xi, heating, m_f, inv_m_width, a_s, inv_a_width):
    """dxi/du on the printed branch (eqs. 4.22-4.24) at effective temperatures u_A, u_M.

    Heating: dz+/du (xi - z-)/(z+ - z-); cooling: dz-/du (z+ - xi)/(z+ - z-), with
    zero-stress transformation temperatures, the band as :func:`band` gives it. The ratio is
    the state's relative position inside the band. It is kept >= 0 so that a state outside
    the band (O(du^2) step error) never transforms backwards (heating never forms
    martensite); above 1 it is left as printed, which pulls such a state back onto the
    active branch.
    """
    zp, dzp = heating_branch(u_a, a_s, inv_a_width)
    zm, dzm = cooling_branch(u_m, m_f, inv_m_width)
    gap = zp - zm
    inside = xi - zm if heating else zp - xi
    ratio = inside / gap if gap > BRANCH_GAP_FLOOR else 1.0
    slope = dzp if heating else dzm
    if ratio < 0.0:
        ratio = 0.0
    return slope * ratio


@jit_inline
def scaled_branch(u, heating, u_r, xi_r, z_r, u_t, xi_t, z_t, m_f, inv_m_width, a_s, inv_a_width):
    """Major branch scaled through reversal point r and target t, for u strictly between.

    Returns xi and dxi/du. Where the active branch is flat to machine precision between the
    two points (both far outside its band) the scaling is 0/0; the branch is then the
    straight line between them, which still closes the loop at t.
    """
    # the band is picked before the exp, so the batch's vector loop evaluates one branch, not both
    z, dz = _tanh_branch(u, a_s if heating else m_f, inv_a_width if heating else inv_m_width)
    den = z_r - z_t
    if abs(den) > BRANCH_GAP_FLOOR:
        frac, dfrac = (z - z_t) / den, dz / den
    else:
        frac, dfrac = (u - u_t) / (u_r - u_t), 1.0 / (u_r - u_t)
    return xi_t + (xi_r - xi_t) * frac, (xi_r - xi_t) * dfrac


@jit
def memory_branch(
    u_a, u_m, heating, memory, n_points, xi0, u_a0, u_m0, slope0, m_f, inv_m_width, a_s, inv_a_width
):
    """xi reached at (u_a, u_m) moving from the state (u_a0, u_m0, xi0) in one direction.

    ``memory[POINT_SIZE * k + (0, 1, 2, 3, 4)]`` is reversal point k (u_A, u_M, xi, z+, z-),
    the top at ``n_points - 1``. ``slope0`` is the printed law's dxi/du at the start state
    (transformation_slope), used while the state stays on an outermost branch. Returns
    (xi, dxi/du, loops closed on the way); the caller commits the closures
    (n_points - 2 * loops) once the step's u is final. Behind the start point the state
    does not move, so xi(u) is continuous and never increasing in u.
    """
    closed = 0
    xi_s, ua_s, um_s, slope = xi0, u_a0, u_m0, slope0
    u = u_a if heating else u_m
    col = 0 if heating else 1
    zcol = 3 if heating else 4
    while n_points - 2 * closed >= 2:
        r = POINT_SIZE * (n_points - 2 * closed - 1)
        t = r - POINT_SIZE
        u_s = ua_s if heating else um_s
        u_t = memory[t + col]
        if (u <= u_s) if heating else (u >= u_s):
            return xi_s, 0.0, closed
        if (u < u_t) if heating else (u > u_t):
            xi, dxi = scaled_branch(
                u,
                heating,
                memory[r + col],
                memory[r + 2],
                memory[r + zcol],
                u_t,
                memory[t + 2],
                memory[t + zcol],
                m_f,
                inv_m_width,
                a_s,
                inv_a_width,
            )
            return xi, dxi, closed
        xi_s, ua_s, um_s = memory[t + 2], memory[t], memory[t + 1]
        closed += 1
        slope = transformation_slope(ua_s, um_s, xi_s, heating, m_f, inv_m_width, a_s, inv_a_width)
    du = u_a - ua_s if heating else u_m - um_s
    if (du <= 0.0) if heating else (du >= 0.0):
        return xi_s, 0.0, closed
    return xi_s + slope * du, slope, closed


@jit
def push_reversal(memory, n_points, u_a, u_m, xi, m_f, inv_m_width, a_s, inv_a_width):
    """Record a reversal point; returns the new count. Full: forget the innermost loop first."""
    if n_points + 1 > MEMORY_DEPTH:
        n_points -= 2
    k = POINT_SIZE * n_points
    memory[k] = u_a
    memory[k + 1] = u_m
    memory[k + 2] = xi
    memory[k + 3] = heating_branch(u_a, a_s, inv_a_width)[0]
    memory[k + 4] = cooling_branch(u_m, m_f, inv_m_width)[0]
    return n_points + 1
