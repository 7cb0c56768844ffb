"""A thin-film or multilayer coating as an interface between two media: its RGB reflectance and
transmittance per direction, and its lobes (a delta pair when smooth, Walter et al.'s GGX pair
with the coating's R and T at the half-vector when rough) restricted to a chosen set of sides.

``thinfilm`` builds a :class:`Coating` from its parameters; the layered walk
(:mod:`renderer.materials.layered`, interface kind FILM) carries one as its top interface, so the
same optics and colour conversion serve both. The outer medium is where the normal points; the
substrate lies below. ``clear`` says whether light can cross into the substrate: false for an
opaque one (T is dropped, and light never arrives from below), true for a clear one (then hits
from below see the media swapped and a stack reversed).

``balanced`` is for coatings over a clear substrate, which paths cross many times (refraction in
and out, the layered walk): with spectral:N, R and T are jittered estimates whose white is 1 only
on average, and clipping R ≤ 1 under total internal reflection (R ≡ 1) then loses what the
estimate overshoots: some 1 % per channel at N = 16 over a white base, and 7–9 % in red and blue
at N = 8 for a coated glass sphere in a white furnace (0.926, 0.981, 0.914; balanced: 1.000).
Dividing both by the same jitter's estimate of white makes a flat spectrum exact at every sample,
so R + T = 1 per channel for lossless media (a ratio estimator: consistent, with a bias of order
1/N² in the colour instead of a loss at every bounce).

``table_first`` > 0 (the thin-film mode ``table``): R and T are read from the material's baked
table over the angle (:mod:`renderer.optics.angular_table`), the 1 nm reference itself, white
exactly; there is no wavelength jitter to balance.
"""
from __future__ import annotations

import warp as wp

from renderer.color.rgb_weights import RgbWeightTable, sampled_white
from renderer.materials.bsdf import (GLOSSY, REFLECTION, SPECULAR, TRANSMISSION, BSDFEval, BSDFSample, delta_sample,
                                     failed_sample, reflect_z, refract, sampled)
from renderer.materials.microfacet import (ggx_D, ggx_G, ggx_sample_visible, ggx_visible_pdf, half_vector,
                                           is_smooth)
from renderer.optics.angular_table import table_locate, table_value
from renderer.optics.multilayer import multilayer_rgb3, multilayer_rgb_sampled
from renderer.optics.thin_film import thin_film_rgb3, thin_film_rgb_sampled
from renderer.vecmath import mean3

BOTH_SIDES = wp.constant(REFLECTION | TRANSMISSION)


@wp.struct
class Coating:
    n_outer: float
    n_film: float                    # one film's index (unused by a stack)
    n_inner: wp.vec2                 # the substrate, n + ik
    d: float                         # one film's thickness, or a stack's mapped total (nm)
    total: float                     # a stack's unmapped total thickness (nm): d / total scales its layers
    clear: bool                      # the substrate is crossed (T kept, hits from below allowed)
    balanced: bool                   # spectral:N estimates divided by the same estimate of white
    layers: wp.array(dtype=wp.vec4)  # the scene's layer table (renderer.materials.stack)
    layer_first: int
    layer_count: int                 # 0: one film
    spectral_n: int                  # 0: rgb3; else wavelengths per evaluation
    table_first: int                 # the baked RGB (R, T) table over the angle in layers; 0: none
    wavelength_u: float
    spectral: RgbWeightTable


@wp.struct
class CoatingRT:
    """A coating's RGB reflectance and transmittance, returned by value from the out-of-line optics: in
    registers, where two output references would hold each call site's (R, T) in the stack frame."""
    r: wp.vec3
    t: wp.vec3


def _coating_optics(n_outer: float, n_film: float, n_inner: wp.vec2, d: float, total: float, clear: bool,
                    balanced: bool, layer_rows: wp.uint64, row_count: int, layer_first: int, layer_count: int,
                    spectral_n: int, table_first: int, wavelength_u: float, weight_rows: wp.uint64, weight_count: int,
                    lambda_min: float, step: float, cos_w: float) -> CoatingRT:
    """RGB (R, T) of the coating for light arriving at cosine cos_w to its normal (negative: from
    the substrate side), each clipped to [0, 1]: a film colour outside the sRGB gamut has a negative
    channel, which a path's throughput must not carry. Rough lobes pass the cosine to the
    microfacet normal.

    R + T is not clipped. With rgb3 it is 1 to float precision for lossless media; with
    spectral:N it is the jittered estimate of white, 1 ± 1e-3 at N = 32 and exactly 1 on average,
    so clipping the sum would bias every image darker (about 0.3 % in a glass-sphere furnace).

    Takes the :class:`Coating`'s fields one by one and its two tables as their rows' addresses and
    counts (``layer_rows``, ``row_count``; ``weight_rows``, ``weight_count``): an out-of-line call then
    passes 23 words in registers instead of a 44-word record (28 of them two array descriptors)
    that the callee copied to its stack frame (docs/gpu.md, "The coating's call")."""
    layers = wp.array(ptr=layer_rows, shape=(row_count,), dtype=wp.vec4)
    spectral = RgbWeightTable()
    spectral.w = wp.array(ptr=weight_rows, shape=(weight_count,), dtype=wp.vec3)
    spectral.lambda_min = lambda_min
    spectral.step = step
    n0 = n_outer
    n2 = n_inner
    back = cos_w < 0.0 and clear
    if back:
        n0 = n_inner[0]
        n2 = wp.vec2(n_outer, 0.0)
    n1 = wp.vec2(n_film, 0.0)
    cos0 = wp.abs(cos_w)
    r = wp.vec3(0.0)
    t = wp.vec3(0.0)
    if table_first > 0:
        # the thin-film mode "table": the front side's table, then (clear substrates) the back's
        first = table_first
        if back:
            first = first + 1 + 2 * int(layers[first][0])
        at = table_locate(layers, first, cos0)
        r = table_value(layers, first, 2, 0, at)
        t = table_value(layers, first, 2, 1, at)
    elif layer_count > 0:
        # a stack: d is its mapped total thickness, which scales every layer alike
        scale = wp.where(total > 0.0, d / total, 1.0)
        if spectral_n > 0:
            r, t = multilayer_rgb_sampled(cos0, n0, n2, layers, layer_first, layer_count, back, scale,
                                          spectral_n, wavelength_u, spectral)
        else:
            r, t = multilayer_rgb3(cos0, n0, n2, layers, layer_first, layer_count, back, scale)
    elif spectral_n > 0:
        r, t = thin_film_rgb_sampled(cos0, n0, n1, n2, d, spectral_n, wavelength_u, spectral)
    else:
        r, t = thin_film_rgb3(cos0, n0, n1, n2, d)
    if balanced and spectral_n > 0 and table_first == 0:
        white = sampled_white(spectral, spectral_n, wavelength_u)
        if wp.min(white[0], wp.min(white[1], white[2])) > 0.0:
            r = wp.cw_div(r, white)
            t = wp.cw_div(t, white)
    r = wp.min(wp.max(r, wp.vec3(0.0)), wp.vec3(1.0))
    t = wp.min(wp.max(t, wp.vec3(0.0)), wp.vec3(1.0))
    if not clear:
        t = wp.vec3(0.0)
    rt = CoatingRT()
    rt.r = r
    rt.t = t
    return rt


def _coating_rgb(optics: wp.Function, name: str) -> wp.Function:
    """``name(c: Coating, cos_w) -> (R, T)``: ``optics`` (:func:`_coating_optics`) on the coating's fields."""

    def rgb(c: Coating, cos_w: float):
        rt = wp.static(optics)(c.n_outer, c.n_film, c.n_inner, c.d, c.total, c.clear, c.balanced, c.layers.ptr,
                               c.layers.shape[0], c.layer_first, c.layer_count, c.spectral_n, c.table_first,
                               c.wavelength_u, c.spectral.w.ptr, c.spectral.w.shape[0], c.spectral.lambda_min,
                               c.spectral.step, cos_w)
        return rt.r, rt.t

    return wp.func(rgb, name=name, inline=True)


#: Out of line: a thin film's BSDF and its layered walk call it from some fifteen places, each a copy
#: of every optics branch (table, stack, film; rgb3 and spectral) when inlined. One copy took the
#: beach's thin-film shading kernel on sm_90 from 3.4 MB of code and a 5.7 KB frame to 1.8 MB and
#: 3.6 KB, and halved its NVRTC time (docs/gpu.md); CPU images are unchanged.
coating_rgb = _coating_rgb(wp.func(_coating_optics, name="coating_optics", inline=False), "coating_rgb")
#: Inlined, for a kernel that calls it from one place only (the wavefront's lens step): no copy is
#: duplicated, and with no call the compiler allocates the optics together with the caller. The
#: beach's lens step on sm_90 under the register cap: a 1,200 B frame out of line, 864 B inlined.
coating_rgb_inlined = _coating_rgb(wp.func(_coating_optics, name="coating_optics_inlined", inline=True),
                                   "coating_rgb_inlined")


@wp.func
def glossy_reflection(wo: wp.vec3, wi: wp.vec3, wm: wp.vec3, r: wp.vec3, alpha: wp.vec2) -> BSDFEval:
    """D G R / (4 |cos θo cos θi|) and the visible-normal density of wi (no lobe choice)."""
    ev = BSDFEval()
    ev.f = r * (ggx_D(wm, alpha) * ggx_G(wo, wi, alpha) / wp.abs(4.0 * wi[2] * wo[2]))
    ev.pdf = ggx_visible_pdf(wo, wm, alpha) / (4.0 * wp.abs(wp.dot(wo, wm)))
    return ev


@wp.func
def coating_eval(c: Coating, eta: float, alpha: wp.vec2, wo: wp.vec3, wi: wp.vec3, sides: int,
                 radiance: bool) -> BSDFEval:
    """The rough coated interface (eta: substrate over outer index): Walter et al.'s BSDF with the
    coating's RGB R and T at the facet in place of F and 1 − F; the density is that of
    :func:`coating_sample` with the same ``sides`` (with both, reflection or refraction is picked
    by their mean at the facet). ``radiance`` false: no 1/eta'² on refraction. A smooth coating
    has delta lobes only: no value here."""
    ev = BSDFEval()
    h = half_vector(wo, wi, eta)      # the facet normal (xyz) and eta' (w; 0: no facet)
    if is_smooth(alpha) or h[3] == 0.0:
        return ev
    wm = wp.vec3(h[0], h[1], h[2])
    r, t = coating_rgb(c, wp.dot(wo, wm))
    total = mean3(r) + mean3(t)
    if total <= 0.0:
        return ev
    if wo[2] * wi[2] > 0.0:
        if (sides & REFLECTION) == 0 or mean3(r) <= 0.0:
            return ev
        ev = glossy_reflection(wo, wi, wm, r, alpha)
        if sides == BOTH_SIDES:
            ev.pdf = ev.pdf * mean3(r) / total
        return ev
    if (sides & TRANSMISSION) == 0 or mean3(t) <= 0.0:
        return ev
    denom = wp.dot(wi, wm) + wp.dot(wo, wm) / h[3]
    denom2 = denom * denom
    g = ggx_D(wm, alpha) * ggx_G(wo, wi, alpha) * wp.abs(wp.dot(wi, wm) * wp.dot(wo, wm) / (denom2 * wi[2] * wo[2]))
    if radiance:
        g = g / (h[3] * h[3])
    ev.f = t * g
    ev.pdf = ggx_visible_pdf(wo, wm, alpha) * wp.abs(wp.dot(wi, wm)) / denom2
    if sides == BOTH_SIDES:
        ev.pdf = ev.pdf * mean3(t) / total
    return ev


@wp.func
def _reflects(r: wp.vec3, t: wp.vec3, sides: int, u: float) -> bool:
    """Reflection or refraction, in proportion to the mean R and T when both sides may be sampled."""
    if sides == BOTH_SIDES:
        return u * (mean3(r) + mean3(t)) < mean3(r)
    return sides == REFLECTION


@wp.func
def smooth_coating_sample(c: Coating, eta: float, wo: wp.vec3, u: float, sides: int, radiance: bool) -> BSDFSample:
    """The delta mirror or refraction, weighted R / p or T / p (and 1/eta'² in radiance mode)."""
    r, t = coating_rgb(c, wo[2])
    p_r = wp.where(mean3(r) > 0.0, 1.0, 0.0)
    if sides == BOTH_SIDES:
        total = mean3(r) + mean3(t)
        if total <= 0.0:
            return failed_sample()
        p_r = mean3(r) / total
    if _reflects(r, t, sides, u):
        if p_r <= 0.0:
            return failed_sample()
        return delta_sample(reflect_z(wo), r / p_r, p_r, REFLECTION | SPECULAR)
    p_t = 1.0 - wp.where(sides == BOTH_SIDES, p_r, 0.0)
    refr = refract(wo, wp.vec3(0.0, 0.0, 1.0), eta)
    if refr[3] == 0.0 or mean3(t) <= 0.0 or p_t <= 0.0:
        return failed_sample()
    w = t / p_t
    if radiance:
        w = w / (refr[3] * refr[3])
    s = delta_sample(wp.vec3(refr[0], refr[1], refr[2]), w, p_t, TRANSMISSION | SPECULAR)
    s.eta = refr[3]
    return s


@wp.func
def coating_sample(c: Coating, eta: float, alpha: wp.vec2, wo: wp.vec3, u: wp.vec3, sides: int,
                   radiance: bool) -> BSDFSample:
    """A reflected or refracted direction (only from ``sides``), smooth or rough (a visible
    microfacet normal, then R or T there); see :func:`coating_eval`."""
    if is_smooth(alpha):
        return smooth_coating_sample(c, eta, wo, u[2], sides, radiance)
    wm = ggx_sample_visible(wo, alpha, wp.vec2(u[0], u[1]))
    r, t = coating_rgb(c, wp.dot(wo, wm))
    if mean3(r) + mean3(t) <= 0.0:
        return failed_sample()
    if _reflects(r, t, sides, u[2]):
        wi = wm * (2.0 * wp.dot(wo, wm)) - wo
        if wi[2] * wo[2] <= 0.0:
            return failed_sample()
        return sampled(wo, wi, coating_eval(c, eta, alpha, wo, wi, sides, radiance), GLOSSY)
    refr = refract(wo, wm, eta)
    wt = wp.vec3(refr[0], refr[1], refr[2])
    if refr[3] == 0.0 or wt[2] * wo[2] >= 0.0:
        return failed_sample()
    s = sampled(wo, wt, coating_eval(c, eta, alpha, wo, wt, sides, radiance), GLOSSY)
    s.eta = refr[3]
    return s
