"""Subsurface scattering: the step that moves a path's vertex from where light enters an object to
where it leaves, for two materials that share the probe machinery (``probe_chord``):

- ``disney`` (below): a BSSRDF with Burley's normalised diffusion profile (Christensen & Burley
  2015), whose exit points are found by probe rays against the same instance through the
  renderer's BVH, as pbrt-v3 and Arnold do;
- pbrt-v4's ``subsurface`` (``tabulated_scatter``, at the end): its tabulated photon-beam-diffusion
  BSSRDF, exit points on the same material (as pbrt-v4 matches them).

``subsurface_step(features)`` compiles only the steps of the materials a scene uses.

At a hit on a solid Disney surface with a non-zero ``scatterdistance`` the path takes, at random,
either the surface lobes (the BSDF without its diffuse base) or this route:

1. pick a colour channel (1/3 each) and a probe axis (the geometric normal 1/2, each tangent 1/4);
2. sample a radius r from that channel's profile R(r) = A s (e^{-sr} + e^{-sr/3}) / (8π r), with
   s = (1.9 − A + 3.5 (A − 0.8)²) / scatterdistance (the paper's fit for diffuse transmission);
3. trace the chord of a sphere of radius R_MAX·d_max through the disk point, parallel to the axis,
   with sequential closest-hit queries (never two nested BVH loops), keeping one of the hits on
   the same instance uniformly (reservoir sampling);
4. weight by R(|p_i − p_o|) · n_found / pdf, the pdf summed over the three axes and channels
   (one-sample MIS between axes), and continue from p_i with the exit lobe (1 − F_i/2)/π.

Open meshes. A half-space is exactly what the profile assumes, so a displaced plane (the sand
patch) needs nothing special: probes along the normal find the plane around p_o, and probes
along the tangents, which miss on flat ground, are accounted for by the MIS pdf. Where a probe
finds nothing of the same instance (beyond the edge of an open patch, or on geometry smaller
than the profile) that sample carries no energy: light that would have travelled further than
the geometry is lost, so edges within a few scatter distances darken slightly. Returning that
mass at the entry point instead was tried and rejected: on closed objects smaller than the
profile it double-counts light the far side of the object already returns (a white sphere in a
furnace rose to 1.15).
"""
from __future__ import annotations

from functools import lru_cache

import warp as wp

from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import Hit, Surface, intersect, surface_at
from renderer.geometry.offsets import ray_epsilon
from renderer.materials import dielectric, kind_id
from renderer.materials import subsurface as pbrt_subsurface
from renderer.materials.bsdf import BSDF
from renderer.materials.disney import exit_bsdf, subsurface_lobe
from renderer.vecmath import PI, max3
from renderer.optics.dispersion import sample_wavelength, wavelength_weight
from renderer.color.spectral import LAMBDA_MAX_NM, LAMBDA_MIN_NM
from renderer.materials.beam_diffusion import N_ROWS
from renderer.materials.tabulated_bssrdf import albedo_from_reflectance, probe_radius, profile, sample_radius
from renderer.optics.fresnel import fresnel_dielectric
from renderer.sampling.frames import Frame, frame_from_normal, frame_from_tangent, to_local
from renderer.sampling.rng import hash_u32

DISNEY = wp.constant(kind_id("disney"))
SUBSURFACE = wp.constant(kind_id(pbrt_subsurface.NAME))
#: Probe sphere radius in units of the largest profile scale d = 1/s: the profile's mass beyond
#: it is 0.75 e^{-R_MAX/3} < 1e-3.
R_MAX = wp.constant(24.0)
#: Most hits on one probe chord that are considered (each costs one BVH query).
MAX_PROBE_HITS = 8
#: Probe-axis probabilities: the normal, then the two tangents.
P_NORMAL = wp.constant(0.5)
SEED_SALT = wp.constant(wp.uint32(0x5BD1E995))


@wp.struct
class SubsurfaceStep:
    """Where the path goes on: the (possibly new) surface point, its BSDF and outgoing direction,
    the throughput factor, and the BVH queries spent."""

    s: Surface
    b: BSDF
    wo: wp.vec3
    weight: wp.vec3
    rays: int


@wp.func
def _identity(b: BSDF, s: Surface, wo: wp.vec3) -> SubsurfaceStep:
    """The step that changes nothing: the surface point, its BSDF and direction, weight 1."""
    ev = SubsurfaceStep()
    ev.s = s
    ev.b = b
    ev.wo = wo
    ev.weight = wp.vec3(1.0)
    ev.rays = 0
    return ev


@wp.func
def probe_axes(f: Frame, u: float) -> Frame:
    """The probe's axis (as n) and the axes of its disk (s, t): the normal with probability
    P_NORMAL, else one of the tangents (1/4 each)."""
    out = f
    if u >= P_NORMAL:
        out.n = wp.where(u < 0.75, f.s, f.t)
        out.s = f.n
        out.t = wp.where(u < 0.75, f.t, f.s)
    return out


@wp.struct
class Probe:
    """What a probe chord found: the hits on the wanted surface, one of them chosen uniformly, and
    the BVH queries spent."""

    found: int
    chosen: Hit
    rays: int


@wp.func
def probe_chord(scene: Scene, p: wp.vec3, axis: wp.vec3, e1: wp.vec3, e2: wp.vec3, r: float, r_max: float,
                phi: float, target: int, by_material: bool, rng: wp.uint32) -> Probe:
    """The chord of the sphere of radius r_max about p, parallel to ``axis``, through the point at
    radius r and angle phi in the (e1, e2) plane: sequential closest-hit queries along it (never two
    nested BVH loops), keeping one hit uniformly (reservoir sampling) among those on instance
    ``target``, or with ``by_material`` on shapes of material ``target``."""
    found = int(0)
    chosen = Hit()
    rays = int(0)
    if r < r_max:
        half = wp.sqrt(r_max * r_max - r * r)
        o = p + (e1 * wp.cos(phi) + e2 * wp.sin(phi)) * r + axis * half
        remaining = 2.0 * half
        for k in range(MAX_PROBE_HITS):
            if remaining > 0.0:
                h = intersect(scene.geo, o, -axis, remaining)
                rays += 1
                if h.inst < 0:
                    remaining = 0.0
                else:
                    key = h.inst
                    if by_material:
                        key = scene.shape_material[scene.geo.inst_shape[h.inst]]
                    if key == target:
                        found += 1
                        if wp.randf(rng) * float(found) < 1.0:
                            chosen = h
                    step = h.t + ray_epsilon(o - axis * h.t)
                    o = o - axis * step
                    remaining = remaining - step
    pr = Probe()
    pr.found = found
    pr.chosen = chosen
    pr.rays = rays
    return pr


@wp.func
def profile_scale(albedo: float, mfp: float) -> float:
    """d = 1/s of Burley's profile: the mean free path over Christensen & Burley's fit."""
    a = albedo - 0.8
    return mfp / (1.9 - albedo + 3.5 * a * a)


@wp.func
def diffusion_profile(r: float, d: float) -> float:
    """Burley's normalised diffusion R(r)/A, per unit area: its integral over the plane is 1."""
    return (wp.exp(-r / d) + wp.exp(-r / (3.0 * d))) / (8.0 * PI * d * r)


@wp.func
def sample_profile_radius(d: float, u: wp.vec2) -> float:
    """Radius with density 2πr R(r)/A = ¼ e^{-r/d}/d + ¾ e^{-r/3d}/(3d): a mixture of two exponentials."""
    scale = wp.where(u[0] < 0.25, d, 3.0 * d)
    return -scale * wp.log(1.0 - wp.min(u[1], 0.999999))


@wp.func
def _axis_pdf(delta: wp.vec3, dist2: float, axis: wp.vec3, n_i: wp.vec3, d: wp.vec3) -> float:
    """Area density of reaching p_i by probes along ``axis``, averaged over the three channels."""
    dn = wp.dot(delta, axis)
    r = wp.max(wp.sqrt(wp.max(dist2 - dn * dn, 0.0)), 1.0e-6 * max3(d))
    prof = diffusion_profile(r, d[0]) + diffusion_profile(r, d[1]) + diffusion_profile(r, d[2])
    return prof * wp.abs(wp.dot(n_i, axis)) / 3.0


@wp.func
def subsurface_scatter(scene: Scene, b: BSDF, s: Surface, inst: int, wo: wp.vec3, seed: int) -> SubsurfaceStep:
    """The subsurface step at a hit (see the module docstring); an identity step for materials
    without subsurface scattering."""
    ev = _identity(b, s, wo)
    if b.kind != DISNEY:
        return ev
    side = wp.where(wp.dot(wo, s.ng) < 0.0, -1.0, 1.0)  # entered from the back of the mesh
    lobe = subsurface_lobe(b, wp.dot(wo, s.ns) * side)
    if max3(lobe.mfp) <= 0.0:
        return ev
    # hash the seed: a state drawn from the path's stream would otherwise replay that stream
    rng = wp.rand_init(wp.int32(hash_u32(wp.uint32(seed) ^ SEED_SALT)))
    if wp.randf(rng) >= lobe.prob:
        ev.weight = wp.vec3(1.0 / (1.0 - lobe.prob))  # the surface lobes carry this sample
        return ev
    A = lobe.albedo
    d = wp.vec3(profile_scale(A[0], lobe.mfp[0]), profile_scale(A[1], lobe.mfp[1]), profile_scale(A[2], lobe.mfp[2]))
    floor = 1.0e-4 * max3(d)
    d = wp.vec3(wp.max(d[0], floor), wp.max(d[1], floor), wp.max(d[2], floor))
    f = frame_from_normal(s.ng * side)
    u_axis = wp.randf(rng)
    pa = probe_axes(f, u_axis)
    ch = wp.min(int(wp.randf(rng) * 3.0), 2)
    r = sample_profile_radius(d[ch], wp.vec2(wp.randf(rng), wp.randf(rng)))
    r_max = R_MAX * max3(d)
    phi = 2.0 * PI * wp.randf(rng)
    probe = probe_chord(scene, s.p, pa.n, pa.s, pa.t, r, r_max, phi, inst, False, rng)
    found = probe.found
    chosen = probe.chosen
    rays = probe.rays
    ev.rays = rays
    if found == 0:
        ev.weight = wp.vec3(0.0)  # the profile's mass beyond the geometry leaves the object unseen
        return ev
    si = surface_at(scene.geo, chosen, scene.shape_flip[scene.geo.inst_shape[inst]] != 0)
    delta = si.p - s.p
    dist2 = wp.dot(delta, delta)
    pdf = (P_NORMAL * _axis_pdf(delta, dist2, f.n, si.ng, d)
           + 0.5 * (1.0 - P_NORMAL) * (_axis_pdf(delta, dist2, f.s, si.ng, d) + _axis_pdf(delta, dist2, f.t, si.ng, d)))
    if pdf <= 0.0:
        ev.weight = wp.vec3(0.0)
        return ev
    dist = wp.max(wp.sqrt(dist2), 1.0e-6 * max3(d))
    R = wp.vec3(A[0] * diffusion_profile(dist, d[0]), A[1] * diffusion_profile(dist, d[1]),
                A[2] * diffusion_profile(dist, d[2]))
    ev.weight = R * (lobe.entry * float(found) / (pdf * lobe.prob))
    ev.s = si
    ev.b = exit_bsdf(b)
    ev.wo = si.ns * side
    return ev


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
    (the albedo whose effective albedo is the reflectance, sigma_t = 1 / (scale mfp)), per channel."""
    m = Medium()
    m.to_rgb = wp.identity(n=3, dtype=float)
    scale = b.p[SSS_SLOT.scale][0]
    rows = b.layers
    first = b.table_first
    from_reflectance = (b.flags & pbrt_subsurface.FROM_REFLECTANCE) != 0
    spectral = (b.flags & pbrt_subsurface.SPECTRAL) != 0
    for c in range(3):
        x = float(0.0)       # sigma_a, or the reflectance
        y = float(0.0)       # sigma_s, or the mean free path
        if spectral:
            hs = sample_wavelength((float(c) + u_lambda) / 3.0)
            lam = hs[0]
            x = _spectrum(rows[first + PROFILE_ROWS], lam)
            y = _spectrum(rows[first + PROFILE_ROWS + 1], lam)
            w = wavelength_weight(b.spectral, hs) / 3.0
            m.to_rgb[0, c] = w[0]
            m.to_rgb[1, c] = w[1]
            m.to_rgb[2, c] = w[2]
        elif from_reflectance:
            x = b.p[SSS_SLOT.reflectance][c]
            y = b.p[SSS_SLOT.mfp][c]
        else:
            x = b.p[SSS_SLOT.sigma_a][c]
            y = b.p[SSS_SLOT.sigma_s][c]
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
        m.rho[c] = rho
        m.sigma_t[c] = st
        if st > 0.0:
            m.r_max[c] = probe_radius(rows, first, rho) / st
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
    pdf = float(0.0)
    for c in range(3):
        rm = m.r_max[c]
        if rm > 0.0:
            if r_n < rm:
                pdf += P_NORMAL * profile(b.layers, b.table_first, m.rho[c], m.sigma_t[c], r_n)[1] * wp.abs(wp.dot(n_i, f_n))
            if r_s < rm:
                pdf += 0.5 * (1.0 - P_NORMAL) * profile(b.layers, b.table_first, m.rho[c], m.sigma_t[c], r_s)[1] * wp.abs(wp.dot(n_i, f_s))
            if r_t < rm:
                pdf += 0.5 * (1.0 - P_NORMAL) * profile(b.layers, b.table_first, m.rho[c], m.sigma_t[c], r_t)[1] * wp.abs(wp.dot(n_i, f_t))
    return pdf / 3.0


@wp.func
def _surface_only(ev: SubsurfaceStep, prob: float) -> SubsurfaceStep:
    """The surface route: the dielectric's reflection alone, weighted by 1 / its probability."""
    out = ev
    out.b.flags = ev.b.flags | pbrt_subsurface.SURFACE
    out.weight = wp.vec3(1.0 / prob)
    return out


@wp.func
def tabulated_scatter(scene: Scene, b: BSDF, s: Surface, inst: int, wo: wp.vec3, seed: int) -> SubsurfaceStep:
    """pbrt-v4's subsurface material at a hit from outside: with probability q = 1 − F(cos θo) light
    enters (weight: one sample of the dielectric's transmission, 1/eta² included, over q), crosses
    the body by the tabulated BSSRDF to an exit point found by a probe chord, and continues there
    with the exit lobe Sw; otherwise the vertex keeps the dielectric's reflection (weight 1/(1 − q)).
    pbrt-v4 makes the same choice after sampling the whole dielectric; the split only moves the
    choice before next-event estimation, which then sees the reflection alone (light through the
    transmission lobe of a closed body is blocked by the body itself)."""
    ev = _identity(b, s, wo)
    cos_o = wp.dot(wo, s.ns)
    if cos_o <= 0.0 or wp.dot(wo, s.ng) <= 0.0:
        return ev           # from inside the body: the plain dielectric
    rng = wp.rand_init(wp.int32(hash_u32(wp.uint32(seed) ^ TABULATED_SALT)))
    eta = b.p[SSS_SLOT.eta][0]
    q = 1.0 - fresnel_dielectric(cos_o, eta)
    u_route = wp.randf(rng)
    u_t = wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng))
    if u_route >= q:
        return _surface_only(ev, 1.0 - q)
    f = frame_from_tangent(s.ns, s.dpdu)
    alpha = pbrt_subsurface.surface_alpha(b)
    t = dielectric.dielectric_sample(eta, alpha, to_local(f, wo), u_t, dielectric.TRANSMISSION, True)
    if t.pdf <= 0.0:
        ev.weight = wp.vec3(0.0)
        return ev
    m = _body(b, wp.randf(rng))
    ch = wp.min(int(wp.randf(rng) * 3.0), 2)
    u_axis = wp.randf(rng)
    u_r = wp.randf(rng)
    phi = 2.0 * PI * wp.randf(rng)
    pa = probe_axes(f, u_axis)
    rm = m.r_max[ch]
    if rm <= 0.0:
        ev.weight = wp.vec3(0.0)
        return ev
    r = sample_radius(b.layers, b.table_first, m.rho[ch], u_r) / m.sigma_t[ch]
    if r < 0.0 or r >= rm:
        ev.weight = wp.vec3(0.0)
        return ev
    material = scene.shape_material[scene.geo.inst_shape[inst]]
    probe = probe_chord(scene, s.p, pa.n, pa.s, pa.t, r, rm, phi, material, True, rng)
    ev.rays = probe.rays
    if probe.found == 0:
        ev.weight = wp.vec3(0.0)
        return ev
    shape_i = scene.geo.inst_shape[probe.chosen.inst]
    si = surface_at(scene.geo, probe.chosen, scene.shape_flip[shape_i] != 0)
    delta = si.p - s.p
    pdf = _tabulated_pdf(b, m, delta, f.s, f.t, f.n, si.ng)
    if pdf <= 0.0:
        ev.weight = wp.vec3(0.0)
        return ev
    dist = wp.length(delta)
    sp = wp.vec3(profile(b.layers, b.table_first, m.rho[0], m.sigma_t[0], dist)[0],
                 profile(b.layers, b.table_first, m.rho[1], m.sigma_t[1], dist)[0],
                 profile(b.layers, b.table_first, m.rho[2], m.sigma_t[2], dist)[0])
    ev.weight = m.to_rgb * sp * (t.weight[0] * float(probe.found) / (q * pdf))
    ev.s = si
    ev.b.flags = b.flags | pbrt_subsurface.EXIT
    ev.wo = si.ns
    return ev


@lru_cache(maxsize=None)
def subsurface_step(features: Features) -> wp.Function:
    """``step(scene, b, s, inst, wo, seed) -> SubsurfaceStep`` with the steps of exactly the
    subsurface materials in ``features`` (Disney's only where a disney material is present)."""
    disney_on = features.subsurface and "disney" in features.materials
    tabulated_on = features.subsurface and pbrt_subsurface.NAME in features.materials

    @wp.func
    def step(scene: Scene, b: BSDF, s: Surface, inst: int, wo: wp.vec3, seed: int) -> SubsurfaceStep:
        if wp.static(tabulated_on):
            if b.kind == SUBSURFACE:
                return tabulated_scatter(scene, b, s, inst, wo, seed)
        if wp.static(disney_on):
            return subsurface_scatter(scene, b, s, inst, wo, seed)
        return _identity(b, s, wo)

    return step
