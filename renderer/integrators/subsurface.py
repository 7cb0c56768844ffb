"""Subsurface scattering: the step that moves a path's vertex from where light enters an object to
where it leaves, for two materials that share the probe machinery (``probe_chord``):

- ``disney`` (below): a BSSRDF with Burley's normalised diffusion profile (Christensen & Burley
  2015), whose exit points are found by probe rays against the same instance through the
  renderer's BVH, as pbrt-v3 and Arnold do;
- pbrt-v4's ``subsurface`` (:mod:`renderer.integrators.tabulated_subsurface`): its tabulated
  photon-beam-diffusion BSSRDF, exit points on the same material (as pbrt-v4 matches them).

``subsurface_step(features)`` (there) compiles only the steps of the materials a scene uses.

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

import warp as wp

from renderer.device.scene import Scene
from renderer.geometry.intersect import Hit, Surface, intersect, surface_at
from renderer.geometry.offsets import ray_epsilon
from renderer.materials import kind_id
from renderer.materials import subsurface as pbrt_subsurface
from renderer.materials.bsdf import BSDF
from renderer.materials.disney import EXIT, subsurface_lobe
from renderer.vecmath import PI, max3
from renderer.sampling.frames import Frame, frame_from_normal
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
    """Where the path goes on: the (possibly new) surface point, the flags of its BSDF (the same
    parameters, loaded where light entered; the step marks the exit or the surface route) and its
    outgoing direction, the throughput factor, and the BVH queries spent."""

    s: Surface
    flags: int
    wo: wp.vec3
    weight: wp.vec3
    rays: int
    exit: Hit               # the hit where light leaves (inst -1: the vertex stays where light entered)


@wp.struct
class Exit:
    """A subsurface step as a later kernel shades it (the wavefront's probe step, whose kernel has
    applied the weight and rays): the hit where light leaves (inst -1: the vertex stays), the BSDF's
    flags and the outgoing direction there."""

    hit: Hit
    flags: int
    wo: wp.vec3


@wp.func
def exit_of(ev: SubsurfaceStep) -> Exit:
    out = Exit()
    out.hit = ev.exit
    out.flags = ev.flags
    out.wo = ev.wo
    return out


@wp.func
def exit_surface(scene: Scene, h: Hit) -> Surface:
    """The surface at a probe's hit (the mesh's own orientation, as every hit's)."""
    return surface_at(scene.geo, h, scene.shape_flip[scene.geo.inst_shape[h.inst]] != 0)


@wp.func
def _identity(b: BSDF, s: Surface, wo: wp.vec3) -> SubsurfaceStep:
    """The step that changes nothing: the surface point, its BSDF and direction, weight 1."""
    ev = SubsurfaceStep()
    ev.s = s
    ev.flags = b.flags
    ev.wo = wo
    ev.weight = wp.vec3(1.0)
    ev.rays = 0
    ev.exit.inst = -1
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
    si = exit_surface(scene, chosen)    # chosen.inst is inst
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
    ev.exit = chosen
    ev.flags = b.flags | EXIT
    ev.wo = si.ns * side
    return ev
