"""Complex arithmetic on ``wp.vec2`` (re, im) for the wave-optics functions."""
from __future__ import annotations

import warp as wp

wp.set_module_options({"fast_math": False, "enable_backward": False})


# Imaginary part added to q_0² (see the module docstring): keeps every q off exactly zero.
_Q2_EPS = wp.constant(1.0e-12)


# Denominators below this are roundoff at a degenerate point, never physics.
_TINY = wp.constant(1.0e-30)


@wp.func
def c_mul(a: wp.vec2, b: wp.vec2) -> wp.vec2:
    return wp.vec2(a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0])


@wp.func
def c_div(a: wp.vec2, b: wp.vec2) -> wp.vec2:
    """a / b, scaled by the larger component of b so that |b|² cannot overflow or underflow."""
    if wp.abs(b[0]) >= wp.abs(b[1]):
        t = b[1] / b[0]
        den = b[0] + b[1] * t
        return wp.vec2((a[0] + a[1] * t) / den, (a[1] - a[0] * t) / den)
    t = b[0] / b[1]
    den = b[0] * t + b[1]
    return wp.vec2((a[0] * t + a[1]) / den, (a[1] * t - a[0]) / den)


@wp.func
def c_sqrt(z: wp.vec2) -> wp.vec2:
    """Principal square root (Re ≥ 0; Im takes the sign of Im z, +0 counting as positive).

    The larger component comes from sqrt((|z| + |Re z|)/2) and the smaller from Im z divided by it,
    so neither suffers cancellation (a tiny absorption survives next to a large real part).
    """
    mag = wp.sqrt(z[0] * z[0] + z[1] * z[1])
    t = wp.sqrt(0.5 * (mag + wp.abs(z[0])))
    if t == 0.0:
        return wp.vec2(0.0, 0.0)
    if z[0] >= 0.0:
        return wp.vec2(t, 0.5 * z[1] / t)
    if z[1] < 0.0:
        return wp.vec2(0.5 * wp.abs(z[1]) / t, -t)
    return wp.vec2(0.5 * z[1] / t, t)


@wp.func
def c_expi(phase: float) -> wp.vec2:
    """exp(i·phase)."""
    return wp.vec2(wp.cos(phase), wp.sin(phase))


@wp.func
def c_abs2(z: wp.vec2) -> float:
    return z[0] * z[0] + z[1] * z[1]


@wp.func
def c_conj(z: wp.vec2) -> wp.vec2:
    return wp.vec2(z[0], -z[1])
