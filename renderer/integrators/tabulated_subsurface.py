"""pbrt-v4's ``subsurface`` material's step (its tabulated photon-beam-diffusion BSSRDF, exit points
on the same material, as pbrt-v4 matches them) on the probe machinery of
:mod:`renderer.integrators.subsurface`, and ``subsurface_step(features)``, which compiles only the
steps of the subsurface materials a scene uses (Disney's, with a film where one has it, and this one).

A film or stack on the boundary (:mod:`renderer.materials.film_body`) changes where light enters
(its T and R in place of 1 − F and F) and how the exit lobe is weighted; it is compiled in only
where some material of the scene has one (``Features.coated_body``).
"""
from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import warp as wp

from renderer.color.spectral import LAMBDA_MAX_NM, LAMBDA_MIN_NM
from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import Surface
from renderer.integrators.subsurface import (P_NORMAL, SUBSURFACE, SubsurfaceStep, _identity, exit_surface,
                                             probe_axes, probe_chord, subsurface_scatter)
from renderer.materials import dielectric, disney
from renderer.materials import subsurface as pbrt_subsurface
from renderer.materials.beam_diffusion import N_ROWS
from renderer.materials.bsdf import BSDF
from renderer.materials.disney_film import entry_factor
from renderer.materials.film_body import entry_share, entry_weight, exit_balance
from renderer.materials.tabulated_bssrdf import (albedo_from_reflectance, effective_albedo, probe_radius, profile,
                                                 sample_radius)
from renderer.optics.dispersion import sample_wavelength, wavelength_weight
from renderer.optics.fresnel import fresnel_dielectric
from renderer.sampling.frames import frame_from_tangent, to_local
from renderer.sampling.rng import hash_u32
from renderer.vecmath import PI, component, with_component

# --- pbrt-v4's subsurface material -------------------------------------------------------------

TABULATED_SALT = wp.constant(wp.uint32(0x27D4EB2F))
SSS_SLOT = pbrt_subsurface.SLOT
#: The spectral body's coefficient rows follow the profile table.
PROFILE_ROWS = wp.constant(N_ROWS)
LAMBDA_MIN = wp.constant(LAMBDA_MIN_NM)
LAMBDA_MAX = wp.constant(LAMBDA_MAX_NM)


@wp.struct
class Medium:
    """The body at the entry point, per channel: an RGB channel, or with SPECTRAL one of three
    wavelengths (pbrt-v4's visible-wavelength density, stratified in thirds of its CDF, jittered
    together, as pbrt-v4 spreads its four); ``to_rgb`` turns the three channels' values into RGB
    (identity, or each wavelength's CIE 1931/D65 to sRGB weight over three times its density: an
    unbiased estimate of the spectrum's RGB, which may be negative in a channel)."""

    rho: wp.vec3
    sigma_t: wp.vec3
    r_max: wp.vec3          # per channel the probe radius (0: the channel cannot be sampled)
    to_rgb: wp.mat33


@wp.func
def _spectrum(row: wp.vec4, lam: float) -> float:
    """A sigmoid-quadratic spectrum (renderer.color.rgb_spectrum) at λ: scale row[3], coefficients row[0:3]."""
    t = (lam - LAMBDA_MIN) / (LAMBDA_MAX - LAMBDA_MIN)
    x = row[0] * t * t + row[1] * t + row[2]
    return row[3] * (0.5 + x / (2.0 * wp.sqrt(1.0 + x * x)))


@wp.func
def _body(b: BSDF, u_lambda: float) -> Medium:
    """sigma_s / sigma_t and sigma_t from the coefficients times scale, or from reflectance and mfp
    (the albedo whose effective albedo is the reflectance, sigma_t = 1 / (scale mfp)), per channel.
    The slots are read at constant rows and the channels set by selects: a run-time index into
    either would keep them in local memory on CUDA (four copies of the 192 B slots, docs/gpu.md)."""
    m = Medium()
    scale = b.p[SSS_SLOT.scale][0]
    rows = b.layers
    first = b.table_first
    from_reflectance = (b.flags & pbrt_subsurface.FROM_REFLECTANCE) != 0
    spectral = (b.flags & pbrt_subsurface.SPECTRAL) != 0
    xs = wp.where(from_reflectance, b.p[SSS_SLOT.reflectance], b.p[SSS_SLOT.sigma_a])  # sigma_a, or the reflectance
    ys = wp.where(from_reflectance, b.p[SSS_SLOT.mfp], b.p[SSS_SLOT.sigma_s])          # sigma_s, or the mean free path
    to_r = wp.vec3(1.0, 0.0, 0.0)   # the rows of to_rgb
    to_g = wp.vec3(0.0, 1.0, 0.0)
    to_b = wp.vec3(0.0, 0.0, 1.0)
    for c in range(3):
        x = component(xs, c)
        y = component(ys, c)
        if spectral:
            hs = sample_wavelength((float(c) + u_lambda) / 3.0)
            lam = hs[0]
            x = _spectrum(rows[first + PROFILE_ROWS], lam)
            y = _spectrum(rows[first + PROFILE_ROWS + 1], lam)
            w = wavelength_weight(b.spectral, hs) / 3.0
            to_r = with_component(to_r, c, w[0])
            to_g = with_component(to_g, c, w[1])
            to_b = with_component(to_b, c, w[2])
        rho = float(0.0)
        st = float(0.0)
        if from_reflectance:
            mfp = scale * y
            if mfp > 0.0:
                st = 1.0 / mfp
                rho = albedo_from_reflectance(rows, first, x)
        else:
            sa = wp.max(scale * x, 0.0)
            ss = wp.max(scale * y, 0.0)
            st = sa + ss
            if st > 0.0:
                rho = ss / st
        r_max = float(0.0)
        if st > 0.0:
            r_max = probe_radius(rows, first, rho) / st
        m.rho = with_component(m.rho, c, rho)
        m.sigma_t = with_component(m.sigma_t, c, st)
        m.r_max = with_component(m.r_max, c, r_max)
    m.to_rgb = wp.matrix_from_rows(to_r, to_g, to_b)
    return m


@wp.func
def _tabulated_pdf(b: BSDF, m: Medium, delta: wp.vec3, f_s: wp.vec3, f_t: wp.vec3, f_n: wp.vec3,
                   n_i: wp.vec3) -> float:
    """Area density of reaching p_i = p_o + delta: per channel (1/3 each) and axis (normal 1/2, each
    tangent 1/4) the radius density at the radius projected along that axis, times |n_i . axis|, where
    that radius lies inside the channel's probe sphere."""
    x = wp.dot(delta, f_s)
    y = wp.dot(delta, f_t)
    z = wp.dot(delta, f_n)
    r_s = wp.sqrt(y * y + z * z)
    r_t = wp.sqrt(z * z + x * x)
    r_n = wp.sqrt(x * x + y * y)
    r_axis = wp.vec3(r_n, r_s, r_t)
    cos_axis = wp.vec3(wp.abs(wp.dot(n_i, f_n)), wp.abs(wp.dot(n_i, f_s)), wp.abs(wp.dot(n_i, f_t)))
    pdf = float(0.0)
    for k in range(9):      # channel k // 3, axis k % 3 (the normal, then the tangents): one profile site
        c = k // 3
        axis = k % 3
        rm = component(m.r_max, c)
        r = component(r_axis, axis)
        if rm > 0.0 and r < rm:
            p_axis = wp.where(axis == 0, P_NORMAL, 0.5 * (1.0 - P_NORMAL))
            pdf += p_axis * profile(b.layers, b.table_first, component(m.rho, c), component(m.sigma_t, c), r)[1] \
                * component(cos_axis, axis)
    return pdf / 3.0


@wp.func
def _surface_only(ev: SubsurfaceStep, prob: float) -> SubsurfaceStep:
    """The surface route: the dielectric's reflection alone, weighted by 1 / its probability."""
    out = ev
    out.flags = ev.flags | pbrt_subsurface.SURFACE
    out.weight = wp.vec3(1.0 / prob)
    return out


@wp.struct
class Entry:
    """The boundary where a path arrives from outside: the probability q of entering and, given
    entry, the refracted sample's weight (per channel: a film's T differs between them)."""

    q: float
    weight: wp.vec3


@wp.func
def _bare_entry_share(b: BSDF, cos_o: float) -> float:
    return 1.0 - fresnel_dielectric(cos_o, b.p[SSS_SLOT.eta][0])


@wp.func
def _bare_entry_weight(b: BSDF, wo_local: wp.vec3, u: wp.vec3) -> wp.vec3:
    """One sample of the dielectric's transmission (1/eta² included); 0 where it fails."""
    t = dielectric.dielectric_sample(b.p[SSS_SLOT.eta][0], pbrt_subsurface.surface_alpha(b), wo_local, u,
                                     dielectric.TRANSMISSION, True)
    return wp.where(t.pdf > 0.0, wp.vec3(t.weight[0]), wp.vec3(0.0))


@wp.func
def _coated_entry_share(b: BSDF, cos_o: float) -> float:
    return entry_share(pbrt_subsurface.coating(b), cos_o)


@wp.func
def _rgb_effective_albedo(b: BSDF) -> wp.vec3:
    """rho_eff per RGB channel: the reflectance, or the table's at sigma_s / (sigma_a + sigma_s)."""
    if (b.flags & pbrt_subsurface.FROM_REFLECTANCE) != 0:
        return b.p[SSS_SLOT.reflectance]
    sigma_a = b.p[SSS_SLOT.sigma_a]     # constant rows: see _body
    sigma_s = b.p[SSS_SLOT.sigma_s]
    out = wp.vec3(0.0)
    for c in range(3):
        sa = wp.max(component(sigma_a, c), 0.0)
        ss = wp.max(component(sigma_s, c), 0.0)
        if sa + ss > 0.0:
            out = with_component(out, c, effective_albedo(b.layers, b.table_first, ss / (sa + ss)))
    return out


@wp.func
def _coated_entry_weight(b: BSDF, wo_local: wp.vec3, u: wp.vec3) -> wp.vec3:
    """The film's transmission sample times the exit balance k (renderer.materials.film_body)."""
    c = pbrt_subsurface.coating(b)
    eta = b.p[SSS_SLOT.eta][0]
    w = entry_weight(c, eta, pbrt_subsurface.surface_alpha(b), wo_local, u)
    if w == wp.vec3(0.0):
        return w
    return wp.cw_mul(w, exit_balance(c, eta, _rgb_effective_albedo(b)))


class TabulatedStep(NamedTuple):
    """pbrt-v4's subsurface material's step, whole (``scatter``) or in two parts: the boundary's
    ``entry(b, s, wo, seed) -> Entry`` and the rest, ``entered(scene, b, s, inst, wo, seed, entry)``."""

    entry: wp.Function
    entered: wp.Function
    scatter: wp.Function


@lru_cache(maxsize=None)
def tabulated_scatter(coated: bool) -> TabulatedStep:
    """``scatter(scene, b, s, inst, wo, seed) -> SubsurfaceStep`` for pbrt-v4's subsurface material
    and its parts, with a film's boundary (:mod:`renderer.materials.film_body`) compiled in where ``coated``."""

    @wp.func
    def entry_share_of(b: BSDF, cos_o: float) -> float:
        if wp.static(coated):
            if (b.flags & pbrt_subsurface.FILM) != 0:
                return _coated_entry_share(b, cos_o)
        return _bare_entry_share(b, cos_o)

    @wp.func
    def entry_weight_of(b: BSDF, wo_local: wp.vec3, u: wp.vec3) -> wp.vec3:
        if wp.static(coated):
            if (b.flags & pbrt_subsurface.FILM) != 0:
                return _coated_entry_weight(b, wo_local, u)
        return _bare_entry_weight(b, wo_local, u)

    @wp.func
    def entry_of(b: BSDF, s: Surface, wo: wp.vec3, seed: int) -> Entry:
        """The boundary's entry at a hit from outside (scatter's first draws): q, and where the path
        enters the refracted sample's weight (0 on the surface route, from inside, or where it fails)."""
        arrival = Entry()
        cos_o = wp.dot(wo, s.ns)
        if cos_o <= 0.0 or wp.dot(wo, s.ng) <= 0.0:
            return arrival
        rng = wp.rand_init(wp.int32(hash_u32(wp.uint32(seed) ^ TABULATED_SALT)))
        arrival.q = entry_share_of(b, cos_o)
        u_route = wp.randf(rng)
        u_t = wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng))
        if u_route < arrival.q:
            arrival.weight = entry_weight_of(b, to_local(frame_from_tangent(s.ns, s.dpdu), wo), u_t)
        return arrival

    @wp.func
    def scatter_entered(scene: Scene, b: BSDF, s: Surface, inst: int, wo: wp.vec3, seed: int,
                        arrival: Entry) -> SubsurfaceStep:
        """pbrt-v4's subsurface material at a hit from outside: with probability q = 1 − F(cos θo) (a
        film's mean T over mean R + T) light enters (weight: one sample of the boundary's transmission,
        1/eta² included, over q; a film's also times the exit balance k), crosses
        the body by the tabulated BSSRDF to an exit point found by a probe chord, and continues there
        with the exit lobe Sw; otherwise the vertex keeps the dielectric's reflection (weight 1/(1 − q)).
        pbrt-v4 makes the same choice after sampling the whole dielectric; the split only moves the
        choice before next-event estimation, which then sees the reflection alone (light through the
        transmission lobe of a closed body is blocked by the body itself). ``arrival``: ``entry_of``'s
        at this hit (the wavefront computes a film's in a step of its own: renderer.integrators.film_entry)."""
        ev = _identity(b, s, wo)
        cos_o = wp.dot(wo, s.ns)
        if cos_o <= 0.0 or wp.dot(wo, s.ng) <= 0.0:
            return ev           # from inside the body: the plain dielectric
        q = arrival.q
        w_in = arrival.weight
        rng = wp.rand_init(wp.int32(hash_u32(wp.uint32(seed) ^ TABULATED_SALT)))
        u_route = wp.randf(rng)
        for _ in range(3):      # the entry weight's draws
            wp.randf(rng)
        if u_route >= q:
            return _surface_only(ev, 1.0 - q)
        f = frame_from_tangent(s.ns, s.dpdu)
        if w_in == wp.vec3(0.0):
            ev.weight = w_in
            return ev
        m = _body(b, wp.randf(rng))
        ch = wp.min(int(wp.randf(rng) * 3.0), 2)
        u_axis = wp.randf(rng)
        u_r = wp.randf(rng)
        phi = 2.0 * PI * wp.randf(rng)
        pa = probe_axes(f, u_axis)
        rm = component(m.r_max, ch)
        if rm <= 0.0:
            ev.weight = wp.vec3(0.0)
            return ev
        r = sample_radius(b.layers, b.table_first, component(m.rho, ch), u_r) / component(m.sigma_t, ch)
        if r < 0.0 or r >= rm:
            ev.weight = wp.vec3(0.0)
            return ev
        material = scene.shape_material[scene.geo.inst_shape[inst]]
        probe = probe_chord(scene, s.p, pa.n, pa.s, pa.t, r, rm, phi, material, True, rng)
        ev.rays = probe.rays
        if probe.found == 0:
            ev.weight = wp.vec3(0.0)
            return ev
        si = exit_surface(scene, probe.chosen)
        delta = si.p - s.p
        pdf = _tabulated_pdf(b, m, delta, f.s, f.t, f.n, si.ng)
        if pdf <= 0.0:
            ev.weight = wp.vec3(0.0)
            return ev
        dist = wp.length(delta)
        sp = wp.vec3(0.0)
        for c in range(3):
            sp = with_component(sp, c, profile(b.layers, b.table_first, component(m.rho, c), component(m.sigma_t, c),
                                               dist)[0])
        if wp.static(coated):
            if (b.flags & pbrt_subsurface.FILM) != 0:
                ev.weight = wp.cw_mul(m.to_rgb * sp, w_in) * (float(probe.found) / (q * pdf))
            else:
                ev.weight = m.to_rgb * sp * (w_in[0] * float(probe.found) / (q * pdf))
        else:
            ev.weight = m.to_rgb * sp * (w_in[0] * float(probe.found) / (q * pdf))
        ev.s = si
        ev.exit = probe.chosen
        ev.flags = b.flags | pbrt_subsurface.EXIT
        ev.wo = si.ns
        return ev

    @wp.func
    def scatter(scene: Scene, b: BSDF, s: Surface, inst: int, wo: wp.vec3, seed: int) -> SubsurfaceStep:
        return scatter_entered(scene, b, s, inst, wo, seed, entry_of(b, s, wo, seed))

    return TabulatedStep(entry_of, scatter_entered, scatter)


@wp.func
def disney_film_scatter(scene: Scene, b: BSDF, s: Surface, inst: int, wo: wp.vec3, seed: int) -> SubsurfaceStep:
    """Disney's step, the route through the body weighted by a film's entry factor
    (:func:`renderer.materials.disney_film.entry_factor`: 1 without a film)."""
    ev = subsurface_scatter(scene, b, s, inst, wo, seed)
    if (ev.flags & disney.EXIT) != 0 and (b.flags & disney.FILM) != 0:
        side = wp.where(wp.dot(wo, s.ng) < 0.0, -1.0, 1.0)
        ev.weight = wp.cw_mul(ev.weight, entry_factor(b, wp.dot(wo, s.ns) * side))
    return ev


@lru_cache(maxsize=None)
def subsurface_step(features: Features) -> wp.Function:
    """``step(scene, b, s, inst, wo, seed) -> SubsurfaceStep`` with the steps of exactly the
    subsurface materials in ``features`` (Disney's only where a disney material is present)."""
    disney_on = features.subsurface and "disney" in features.materials
    tabulated_on = features.subsurface and pbrt_subsurface.NAME in features.materials
    coated = features.coated_body
    disney_coated = disney_on and features.coated_disney

    @wp.func
    def step(scene: Scene, b: BSDF, s: Surface, inst: int, wo: wp.vec3, seed: int) -> SubsurfaceStep:
        if wp.static(tabulated_on):
            if b.kind == SUBSURFACE:
                return wp.static(tabulated_scatter(coated).scatter)(scene, b, s, inst, wo, seed)
        if wp.static(disney_coated):
            return disney_film_scatter(scene, b, s, inst, wo, seed)
        if wp.static(disney_on):
            return subsurface_scatter(scene, b, s, inst, wo, seed)
        return _identity(b, s, wo)

    return step
