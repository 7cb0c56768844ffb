"""Multilayer stacks on the device: reflectance and transmittance of outer medium | L layers |
substrate, s and p averaged (Warp functions). Conventions as in :mod:`renderer.optics.thin_film`:
exp(-iωt), n + ik with k ≥ 0, q_j = n_j cos θ_j with Im q_j ≥ 0, signed Fresnel amplitudes, a
real outer index.

Formulation: Rouard's recursion (the Airy sum applied layer by layer from the substrate up),
not the product of Abelès characteristic matrices. Going up, the reflection coefficient Γ of
everything below an interface, referred to the top of the layer beneath it, is

    Γ_above = (r + Γ e) / (1 + r Γ e),   e = exp(2i q d · 2π/λ),

and the transmitted amplitude gathers a factor t / (1 + r Γ e) and exp(iβ) (|exp(iβ)|² = |e|)
per interface. Why: every quantity stays bounded. |e| ≤ 1 because Im q ≥ 0, so a thick absorbing
or evanescent layer only drives e to 0 (the layer becomes opaque, or frustrated TIR stops
tunnelling), where the characteristic matrices hold cosh and sinh of the same exponent and
overflow float32 past ~88 nepers, then cancel catastrophically. Γ is a ratio of amplitudes, not an
amplitude, so 500 layers neither grow nor shrink it; the transmitted power is a product of real
factors that can only underflow to 0, which is the right answer. TIR (an imaginary q), metals (a
complex q) and 0 nm layers (e = 1) go through the same lines, and a layer equal to its neighbour
has bit-identical q (see thin_film's radicand), so r = 0 and t = 1 exactly. For one layer the
recursion is the Airy formula itself.

Layer table rows are ``wp.vec4`` (Cauchy A, Cauchy B in µm², k, thickness in nm): the layer's
index at λ is A + B/λ² (λ in µm) + ik, so dispersion costs nothing when B = 0. A stack is a slice
``layers[first:first + count]`` listed from the outer medium down; ``reverse`` walks it the other
way for light arriving from the substrate side. ``scale`` multiplies every thickness (the
thickness map)."""
from __future__ import annotations

import warp as wp

from renderer.color.rgb_weights import RgbWeightTable, rgb_weight
from renderer.optics.complex import _TINY, c_abs2, c_conj, c_div, c_expi, c_mul, c_sqrt
from renderer.optics.fresnel import normal_component, normal_component_sq
from renderer.optics.thin_film import RGB3_B, RGB3_G, RGB3_R

wp.set_module_options({"fast_math": False, "enable_backward": False})

#: Cauchy's B is given in µm²; wavelengths are in nm.
_UM2_IN_NM2 = wp.constant(1.0e6)


@wp.func
def layer_index(layer: wp.vec4, lambda_nm: float) -> wp.vec2:
    """Complex index of a layer row at a wavelength (Cauchy dispersion of the real part)."""
    return wp.vec2(layer[0] + layer[1] * _UM2_IN_NM2 / (lambda_nm * lambda_nm), layer[2])


@wp.func
def _couple(g: wp.vec2, t2: float, qa: wp.vec2, qb: wp.vec2, wa: wp.vec2, wb: wp.vec2, nn: wp.vec2):
    """One interface a (above) | b (below), for one polarisation: Γ above the interface from Γ
    below it (g, already referred to the interface), and the transmitted power product times
    |t_ab / (1 + r_ab g)|². s: wa = wb = nn = 1; p: wa = n_a², wb = n_b², nn = n_a n_b."""
    x = c_mul(wb, qa)
    y = c_mul(wa, qb)
    den = x + y
    r = c_div(x - y, den)
    t = c_div(c_mul(2.0 * nn, qa), den)
    multiple = wp.vec2(1.0, 0.0) + c_mul(r, g)
    return c_div(r + g, multiple), t2 * c_abs2(t) / wp.max(c_abs2(multiple), _TINY)


@wp.func
def _stack_row(layers: wp.array(dtype=wp.vec4), first: int, count: int, reverse: bool, i: int) -> wp.vec4:
    """The i-th layer counted from the substrate side."""
    return layers[wp.where(reverse, first + i, first + count - 1 - i)]


@wp.func
def multilayer_RT(cos0: float, lambda_nm: float, n0: float, n_sub: wp.vec2, layers: wp.array(dtype=wp.vec4),
                  first: int, count: int, reverse: bool, scale: float) -> wp.vec2:
    """(R, T) of the stack, averaged over s and p, at one wavelength (monochromatic).

    cos0 in [0, 1] (clamped) in the real outer medium n0. T is the power entering the substrate
    (flux factor included; 0 when the substrate wave is evanescent), so R + T = 1 for a lossless
    stack and substrate, and 1 − R − T ≥ 0 is what the layers (and a metal substrate) absorb.
    """
    c = wp.clamp(cos0, 0.0, 1.0)
    q0_sq = normal_component_sq(c, n0)
    q0 = c_sqrt(q0_sq)
    one = wp.vec2(1.0, 0.0)
    n_b = n_sub
    q_b = normal_component(q0_sq, n0, n_b)
    w_b = c_mul(n_b, n_b)
    inv_q0 = 1.0 / wp.max(q0[0], _TINY)
    flux_s = wp.max(q_b[0], 0.0) * inv_q0
    flux_p = wp.max(c_div(c_mul(q_b, c_conj(w_b)), wp.vec2(c_abs2(n_b), 0.0))[0], 0.0) * inv_q0
    g_s = wp.vec2(0.0, 0.0)
    g_p = wp.vec2(0.0, 0.0)
    t_s = float(1.0)
    t_p = float(1.0)
    for i in range(count):
        row = _stack_row(layers, first, count, reverse, i)
        n_a = layer_index(row, lambda_nm)
        q_a = normal_component(q0_sq, n0, n_a)
        w_a = c_mul(n_a, n_a)
        g_s, t_s = _couple(g_s, t_s, q_a, q_b, one, one, one)
        g_p, t_p = _couple(g_p, t_p, q_a, q_b, w_a, w_b, c_mul(n_a, n_b))
        # through layer a: round trip exp(2iβ) in cycles (phase) and nepers (decay)
        d = wp.max(row[3] * scale, 0.0)
        cycles = 2.0 * q_a[0] * d / lambda_nm
        e_abs = wp.exp(-4.0 * wp.pi * q_a[1] * d / lambda_nm)
        e = e_abs * c_expi(2.0 * wp.pi * (cycles - wp.floor(cycles)))
        g_s = c_mul(g_s, e)
        g_p = c_mul(g_p, e)
        t_s = t_s * e_abs
        t_p = t_p * e_abs
        n_b = n_a
        q_b = q_a
        w_b = w_a
    n_0 = wp.vec2(n0, 0.0)
    g_s, t_s = _couple(g_s, t_s, q0, q_b, one, one, one)
    g_p, t_p = _couple(g_p, t_p, q0, q_b, c_mul(n_0, n_0), w_b, c_mul(n_0, n_b))
    r = 0.5 * (c_abs2(g_s) + c_abs2(g_p))
    t = 0.5 * (t_s * flux_s + t_p * flux_p)
    return wp.vec2(wp.clamp(r, 0.0, 1.0), wp.clamp(t, 0.0, 1.0))


@wp.func
def multilayer_rgb3(cos0: float, n0: float, n_sub: wp.vec2, layers: wp.array(dtype=wp.vec4), first: int,
                    count: int, reverse: bool, scale: float):
    """The seed's mode for a stack: (R, T) at 650, 510 and 475 nm used directly as R, G, B."""
    red = multilayer_RT(cos0, RGB3_R, n0, n_sub, layers, first, count, reverse, scale)
    green = multilayer_RT(cos0, RGB3_G, n0, n_sub, layers, first, count, reverse, scale)
    blue = multilayer_RT(cos0, RGB3_B, n0, n_sub, layers, first, count, reverse, scale)
    return wp.vec3(red[0], green[0], blue[0]), wp.vec3(red[1], green[1], blue[1])


@wp.func
def multilayer_rgb_sampled(cos0: float, n0: float, n_sub: wp.vec2, layers: wp.array(dtype=wp.vec4), first: int,
                           count: int, reverse: bool, scale: float, n_samples: int, u_jitter: float,
                           table: RgbWeightTable):
    """Linear-sRGB (R, T) of the stack from n_samples stratified, jittered wavelengths: the same
    unbiased estimator of the CIE integral as :func:`thin_film.thin_film_rgb_sampled`."""
    step = table.step * float(table.w.shape[0] - 1) / float(n_samples)
    r = wp.vec3(0.0)
    t = wp.vec3(0.0)
    for i in range(n_samples):
        lam = table.lambda_min + (float(i) + u_jitter) * step
        rt = multilayer_RT(cos0, lam, n0, n_sub, layers, first, count, reverse, scale)
        w = rgb_weight(table, lam) * step
        r += rt[0] * w
        t += rt[1] * w
    return r, t
