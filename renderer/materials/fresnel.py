"""Fresnel reflectance at a single interface (unpolarised), for dielectrics and conductors."""
from __future__ import annotations

import warp as wp


@wp.func
def fresnel_dielectric(cos_i: float, eta: float) -> float:
    """Reflectance for light arriving with cos θi (negative: from inside) at an interface of
    relative index eta = n_t / n_i; 1 under total internal reflection."""
    c = wp.clamp(cos_i, -1.0, 1.0)
    e = eta
    if c < 0.0:
        e = 1.0 / e
        c = -c
    sin2_t = (1.0 - c * c) / (e * e)
    if sin2_t >= 1.0:
        return 1.0
    cos_t = wp.sqrt(wp.max(0.0, 1.0 - sin2_t))
    r_par = (e * c - cos_t) / (e * c + cos_t)
    r_perp = (c - e * cos_t) / (c + e * cos_t)
    return 0.5 * (r_par * r_par + r_perp * r_perp)


@wp.func
def _fresnel_conductor1(cos_i: float, eta: float, k: float) -> float:
    """Exact unpolarised reflectance of a conductor of complex index eta + i k (from the
    complex Snell's law written in real arithmetic)."""
    c2 = cos_i * cos_i
    s2 = 1.0 - c2
    t0 = eta * eta - k * k - s2
    a2b2 = wp.sqrt(wp.max(0.0, t0 * t0 + 4.0 * eta * eta * k * k))
    a = wp.sqrt(wp.max(0.0, 0.5 * (a2b2 + t0)))
    t1 = a2b2 + c2
    t2 = 2.0 * cos_i * a
    rs = (t1 - t2) / wp.max(t1 + t2, 1.0e-20)
    t3 = c2 * a2b2 + s2 * s2
    t4 = t2 * s2
    rp = rs * (t3 - t4) / wp.max(t3 + t4, 1.0e-20)
    return 0.5 * (rs + rp)


@wp.func
def fresnel_conductor(cos_i: float, eta: wp.vec3, k: wp.vec3) -> wp.vec3:
    c = wp.clamp(wp.abs(cos_i), 0.0, 1.0)
    return wp.vec3(_fresnel_conductor1(c, eta[0], k[0]), _fresnel_conductor1(c, eta[1], k[1]),
                   _fresnel_conductor1(c, eta[2], k[2]))
