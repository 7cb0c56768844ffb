"""Fresnel equations: signed complex amplitudes for films, and the reflectances materials use."""
from __future__ import annotations

import warp as wp

from renderer.optics.complex import _Q2_EPS, c_abs2, c_div, c_mul, c_sqrt


@wp.func
def normal_component_sq(cos0: float, n0: float) -> wp.vec2:
    """q_0² = (n_0 cos θ_0)², regularised (see module docstring)."""
    q0 = n0 * cos0
    return wp.vec2(q0 * q0, _Q2_EPS)


@wp.func
def normal_component(q0_sq: wp.vec2, n0: float, n: wp.vec2) -> wp.vec2:
    """q = n cos θ in a medium of complex index n, from Snell's law; Im q ≥ 0 (decaying)."""
    return c_sqrt(c_mul(wp.vec2(n[0] - n0, n[1]), wp.vec2(n[0] + n0, n[1])) + q0_sq)


@wp.func
def fresnel_amplitudes(qi: wp.vec2, qj: wp.vec2, wi: wp.vec2, wj: wp.vec2, nn: wp.vec2):
    """(r_ij, t_ij, t_ji) for light going from medium i to j.

    One formula for both polarisations: s uses wi = wj = nn = 1; p uses the permittivities
    wi = n_i², wj = n_j² and nn = n_i n_j (then r_p = (n_j² q_i − n_i² q_j)/(n_j² q_i + n_i² q_j),
    Hecht's sign, and t_p is the ratio of electric field amplitudes).
    """
    a = c_mul(wj, qi)
    b = c_mul(wi, qj)
    den = a + b
    two_nn = 2.0 * nn
    return c_div(a - b, den), c_div(c_mul(two_nn, qi), den), c_div(c_mul(two_nn, qj), den)


@wp.func
def fresnel_dielectric(cos_i: float, eta: float) -> float:
    """Unpolarised reflectance of a dielectric interface, eta = n_t / n_i.

    cos_i < 0 means the light arrives from the other side (the eta side): the roles swap, as the
    dielectric material needs when a ray leaves the object. 1 under total internal reflection.
    """
    c = wp.clamp(cos_i, -1.0, 1.0)
    e = eta
    if c < 0.0:
        c = -c
        e = 1.0 / eta
    sin2_t = (1.0 - c * c) / (e * e)
    if sin2_t >= 1.0:
        return 1.0
    cos_t = wp.sqrt(1.0 - sin2_t)
    r_s = (c - e * cos_t) / (c + e * cos_t)
    r_p = (e * c - cos_t) / (e * c + cos_t)
    return 0.5 * (r_s * r_s + r_p * r_p)


@wp.func
def _fresnel_conductor_channel(cos_i: float, eta: float, k: float) -> float:
    n = wp.vec2(eta, k)
    q0_sq = normal_component_sq(cos_i, 1.0)
    q0 = c_sqrt(q0_sq)
    q = normal_component(q0_sq, 1.0, n)
    one = wp.vec2(1.0, 0.0)
    r_s, t_s, u_s = fresnel_amplitudes(q0, q, one, one, one)
    r_p, t_p, u_p = fresnel_amplitudes(q0, q, one, c_mul(n, n), n)
    return 0.5 * (c_abs2(r_s) + c_abs2(r_p))


@wp.func
def fresnel_conductor(cos_i: float, eta: wp.vec3, k: wp.vec3) -> wp.vec3:
    """Unpolarised reflectance per RGB channel of a conductor of relative index eta + i k.

    The side is irrelevant for an opaque conductor, so |cos_i| is used.
    """
    c = wp.min(wp.abs(cos_i), 1.0)
    return wp.vec3(_fresnel_conductor_channel(c, eta[0], k[0]),
                   _fresnel_conductor_channel(c, eta[1], k[1]),
                   _fresnel_conductor_channel(c, eta[2], k[2]))
