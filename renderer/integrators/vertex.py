"""The steps of a path, written once for both integrators: the megakernel
(:mod:`renderer.integrators.path`) calls them in one loop, the wavefront
(:mod:`renderer.integrators.wavefront`) calls each from its own kernel on state kept in memory.
Both therefore draw the same random numbers in the same order and do the same float operations,
and their CPU images agree bit for bit.

- ``start``: the camera ray and the sampler's start for one (pixel, sample index).
- ``arrive``: what the path finds where its ray ends: light leaving the scene, or the emission of
  the surface it hit (MIS-weighted); the end at the maximum depth; the material, mixes resolved.
- ``scatter``: everything at a vertex that is shaded: this bounce's numbers, the material's BSDF,
  dispersion, subsurface scattering, a light sample (as a shadow ray for the caller to trace) and
  the BSDF sample that continues the path, with Russian roulette.
- ``record``: the finished sample into the film, or counted as dropped.

The factories specialise to a :class:`Features`; ``scatter_function`` also to one material kind
(the wavefront's shading kernel per kind) while drawing its numbers as the whole scene's
megakernel does, so the streams stay aligned."""
from __future__ import annotations

import dataclasses
from functools import lru_cache
from typing import NamedTuple

import warp as wp

from renderer.camera import generate_ray
from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import Hit, Surface, surface_at
from renderer.geometry.offsets import offset_origin, ray_epsilon
from renderer.integrators.emission import emitted_adder, escaped_adder
from renderer.integrators.path_state import PathState, ShadowRay
from renderer.integrators.shading import load_bsdf, shading_functions
from renderer.integrators.subsurface import Exit, SubsurfaceStep, exit_surface
from renderer.integrators.tabulated_subsurface import subsurface_step
from renderer.integrators.thin_slab import crosses_thin_slab
from renderer.lights import dispatch
from renderer.lights.sample import light_sampler
from renderer.materials import dielectric, disney, kind_id, subsurface
from renderer.materials.bsdf import SPECULAR
from renderer.materials.selection import choose_material
from renderer.optics.dispersion import sample_wavelength, wavelength_weight
from renderer.pixel_filter import sample_filter
from renderer.sampling.frames import to_local, to_world
from renderer.sampling.mis import power_heuristic
from renderer.sampling.rng import sample_rng
from renderer.sampling.samplers import (BSDF, DIM_BOUNCE, DIM_LENS, DIMS_PER_BOUNCE, LIGHT, LIGHT_CHOICE, LOBE,
                                        ROULETTE, SUBSURFACE, WAVELENGTH, PixelSample, SamplerParams, get_1d, get_2d,
                                        get_pixel_2d, hashed_bits, start_sample)
from renderer.sensor import film_value
from renderer.vecmath import max3

#: The kind id of dielectrics, the material that may disperse.
DIELECTRIC = wp.constant(kind_id(dielectric.NAME))


@wp.struct
class PathStart:
    """A new path and the pixel sample its numbers come from."""

    path: PathState
    sample: PixelSample


@wp.struct
class Arrival:
    """Where the ray ended: ``shade`` says the path goes on at surface ``s`` with material ``m``."""

    path: PathState
    shade: bool
    s: Surface
    m: int


@wp.struct
class Scattered:
    """A shaded vertex: the path's new state, whether it goes on, and its light sample's shadow ray."""

    path: PathState
    alive: bool
    shadow: ShadowRay
    ng: wp.vec3             # the geometric normal where the vertex scattered (media: which side it left by)


class PathFunctions(NamedTuple):
    start: wp.Function      # (scene, smp, seed, sample_index, pixel) -> PathStart
    arrive: wp.Function     # (scene, path, hit, max_depth) -> Arrival
    record: wp.Function     # (scene, path, pixel, film, bad_samples, ray_count)


@lru_cache(maxsize=None)
def path_functions(features: Features, independent: bool) -> PathFunctions:
    """The steps around shading for a scene of ``features`` (see the module docstring)."""
    nee = features.nee
    add_escaped = escaped_adder(*dispatch(features.escaping, "escaped"), nee)   # lights rays leaving the scene see
    emitters, emitter_ids = dispatch(features.lights, "emitted")              # lights on surfaces
    add_emitted = emitted_adder(emitters, emitter_ids, nee)
    mixes = features.mix
    dispersion = features.dispersion

    @wp.func(inline=True)
    def start(scene: Scene, smp: SamplerParams, seed: int, sample_index: int, pixel: int) -> PathStart:
        width = scene.cam.width
        px = pixel % width
        py = pixel // width
        st = PathState()
        out = PathStart()
        rng = sample_rng(seed, sample_index, pixel)
        if wp.static(independent):
            jit = wp.vec2(wp.randf(rng), wp.randf(rng))  # drawn inline: Warp passes rng by value
            u_lens = wp.vec2(wp.randf(rng), wp.randf(rng))
        else:
            ps = start_sample(smp, seed, pixel, px, py, sample_index)
            jit = get_pixel_2d(smp, ps)
            u_lens = get_2d(smp, ps, DIM_LENS)
            out.sample = ps
        fs = sample_filter(scene.cam.filter, jit)      # the pixel filter's offset and weight
        ray = generate_ray(scene.cam, float(px) + fs.p[0], float(py) + fs.p[1], u_lens)
        st.o = ray.o
        st.d = ray.d
        st.L = wp.vec3(0.0)
        st.beta = wp.vec3(1.0)
        st.eta_scale = 1.0
        st.prev_pdf = 0.0
        st.prev_specular = True
        st.prev_p = ray.o
        st.depth = 0
        st.hero = 0.0
        st.weight = fs.weight
        st.rays = 0
        st.rng = rng
        out.path = st
        return out

    @wp.func(inline=True)
    def arrive(scene: Scene, path: PathState, hit: Hit, max_depth: int) -> Arrival:
        st = path
        out = Arrival()
        out.shade = False
        sel = 1.0 / float(wp.max(scene.lights.count, 1))
        if hit.inst < 0:
            st.L = add_escaped(scene.lights, st.o, st.d, st.beta, sel, st.prev_pdf, st.prev_specular, st.L)
            out.path = st
            return out
        shape = scene.geo.inst_shape[hit.inst]
        s = surface_at(scene.geo, hit, scene.shape_flip[shape] != 0)
        wo = -st.d
        if wp.static(len(emitters) > 0):
            li = scene.shape_light[shape]
            if li >= 0:
                st.L = add_emitted(scene.lights, li, st.prev_p, s.p, s.ng, wo, st.beta, sel, st.prev_pdf,
                                   st.prev_specular, st.L)
        out.path = st
        if st.depth >= max_depth:
            return out
        m = scene.shape_material[shape]
        if wp.static(mixes):
            m = choose_material(scene.mat.kind, scene.mat.mix, scene.tex, m, s, wo)
        out.shade = True
        out.s = s
        out.m = m
        return out

    @wp.func(inline=True)
    def record(scene: Scene, st: PathState, pixel: int, film: wp.array(dtype=wp.vec3d),
               bad_samples: wp.array(dtype=int), ray_count: wp.array(dtype=wp.int64)):
        L = st.L
        # a path through dispersive glass carries one wavelength, whose sRGB may have a negative channel
        if wp.isfinite(L) and (wp.static(dispersion) or (L[0] >= 0.0 and L[1] >= 0.0 and L[2] >= 0.0)):
            film[pixel] = film[pixel] + film_value(scene.cam.sensor, L, st.weight)
        else:
            wp.atomic_add(bad_samples, pixel // scene.cam.width, 1)   # per row: no two CPU threads share one
        ray_count[pixel] = ray_count[pixel] + wp.int64(st.rays)       # this thread's pixel alone: no atomic

    return PathFunctions(start, arrive, record)


def moves_vertex(features: Features, kind: str) -> bool:
    """Whether subsurface scattering may move a vertex of ``kind`` before it is shaded: its shading
    frame (and bump map) is then taken where the light leaves, which no earlier step knows."""
    return features.subsurface and kind in (disney.NAME, subsurface.NAME)


#: The parts of a vertex ``scatter_function`` compiles: both (the megakernel, a shading kernel in one
#: piece), the light sample alone (NEE) or the BSDF sample alone (the path's next ray).
WHOLE, LIGHT_SAMPLE, BSDF_SAMPLE = "whole", "light", "bsdf"


@lru_cache(maxsize=None)
def scatter_function(features: Features, independent: bool, kind: str | None = None,
                     bumped: bool = False, probed: bool = False, part: str = WHOLE) -> wp.Function:
    """``scatter(scene, smp, ps, path, hit, s, m, rr_depth, rr_mean, moved) -> Scattered`` at a vertex of material
    ``m`` (of ``kind`` only, when given). The numbers drawn are the scene's: a material that scatters
    below its surface anywhere in the scene takes a subsurface seed at every vertex. ``bumped``: the
    caller put the bump-mapped shading normal in ``s.ns`` (the wavefront's bump step, so a shading
    kernel holds no bump texture program); for a kind whose vertex moves (``moves_vertex``) only
    ``probed``: the wavefront's probe step took the subsurface step (:func:`probe_function`) and
    applied its weight, ``moved`` says where it left the vertex (else ``moved`` is not read), and
    with ``bumped`` the bump step's normal in ``s.ns`` is the one where it left. ``part``:
    ``LIGHT_SAMPLE`` keeps only the light sample (``out.shadow``; ``out.path`` is the state it saw,
    not advanced), ``BSDF_SAMPLE`` only the BSDF sample (``out.shadow.on`` False). Neither needs the
    other's results, and both draw the vertex's numbers, take dispersion and the moved vertex as the
    whole does, so two kernels over one queue, the light part's first, compute what the whole
    computes (the wavefront's split shaders); ``WHOLE`` generates the code it always did."""
    shaded = features if kind is None else dataclasses.replace(features, materials=(kind,))
    draw_sss = features.subsurface
    has_sss = any(moves_vertex(features, k) for k in shaded.materials)
    assert not (bumped and has_sss and not probed), "a moved vertex takes its bump map where it ends"
    shading_frame, eval_pdf, sample_bsdf = shading_functions(dataclasses.replace(shaded, bump=False) if bumped
                                                             else shaded)
    sample_light = light_sampler(*dispatch(features.lights, "sample"))
    light_sampling = features.nee and len(features.lights) > 0 and part != BSDF_SAMPLE
    light_only = part == LIGHT_SAMPLE
    subsurface_scatter = subsurface_step(shaded)
    dispersion = features.dispersion and dielectric.NAME in shaded.materials
    media = features.media
    thin_slabs = features.thin_slabs

    @wp.func(inline=True)
    def scatter(scene: Scene, smp: SamplerParams, ps: PixelSample, path: PathState, hit: Hit, s_hit: Surface,
                m: int, rr_depth: int, rr_mean: float, moved: Exit) -> Scattered:
        st = path
        out = Scattered()
        out.alive = False
        out.shadow.on = False
        s = s_hit
        wo = -st.d
        b = load_bsdf(scene.mat, scene.tex, scene.spectral, scene.spectral_n, m, s)
        # this bounce's numbers, drawn before any of them is used (the same stream order as ever)
        u_sss = int(0)
        if wp.static(independent):
            rng = st.rng
            b.wavelength_u = wp.randf(rng)
            if wp.static(draw_sss):
                u_sss = wp.randi(rng)
            u_sel = wp.randf(rng)
            u_light = wp.vec2(wp.randf(rng), wp.randf(rng))
            u_bsdf = wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng))
            u_rr = wp.randf(rng)
            st.rng = rng
        else:
            dim = DIM_BOUNCE + st.depth * DIMS_PER_BOUNCE
            b.wavelength_u = get_1d(smp, ps, dim + WAVELENGTH)
            if wp.static(draw_sss):
                u_sss = int(hashed_bits(ps, dim + SUBSURFACE))
            u_sel = get_1d(smp, ps, dim + LIGHT_CHOICE)
            u_light = get_2d(smp, ps, dim + LIGHT)
            ub = get_2d(smp, ps, dim + BSDF)
            u_bsdf = wp.vec3(ub[0], ub[1], get_1d(smp, ps, dim + LOBE))
            u_rr = get_1d(smp, ps, dim + ROULETTE)
        if wp.static(dispersion):
            # the first dispersive interface picks the path's wavelength (renderer.optics.dispersion)
            if b.kind == DIELECTRIC and b.table_first > 0:
                if st.hero == 0.0:
                    hs = sample_wavelength(b.wavelength_u)
                    st.hero = hs[0]
                    st.beta = wp.cw_mul(st.beta, wavelength_weight(scene.spectral, hs))
                b = dielectric.dispersed(b, st.hero)
        if wp.static(probed):
            # the probe step moved the vertex (its weight is in st.beta): shade where light leaves
            b.flags = moved.flags
            if moved.hit.inst >= 0:
                s = exit_surface(scene, moved.hit)
                wo = moved.wo
                if wp.static(bumped):
                    if scene.mat.bump[m] >= 0:
                        s.ns = s_hit.ns     # the bump step's, taken where light leaves
        elif wp.static(has_sss):
            # subsurface scattering may move the vertex to where light leaves the object
            sss = subsurface_scatter(scene, b, s, hit.inst, wo, u_sss)
            st.rays = st.rays + sss.rays
            st.beta = wp.cw_mul(st.beta, sss.weight)
            s = sss.s
            b.flags = sss.flags
            wo = sss.wo
        out.ng = s.ng
        frame = shading_frame(scene, m, s)
        wo_l = to_local(frame, wo)

        # next-event estimation: one light, MIS-weighted against BSDF sampling, as a shadow ray
        if wp.static(light_sampling):
            if scene.lights.count > 0:
                ls = sample_light(scene.lights, s.p, u_sel, u_light)
                if ls.pdf > 0.0 and max3(ls.L) > 0.0:
                    wi_l = to_local(frame, ls.wi)
                    fb = eval_pdf(b, wo_l, wi_l)
                    f = fb.f
                    # shading normals must not let light through the geometric surface
                    if wp.dot(ls.wi, s.ng) * wi_l[2] <= 0.0:
                        f = wp.vec3(0.0)
                    f = f * wp.abs(wi_l[2])
                    if max3(f) > 0.0:
                        origin = offset_origin(s, ls.wi)
                        # measured from the offset origin (on a 2 km triangle the offset is mm,
                        # more than a fixed margin), stopping short by pbrt's ShadowEpsilon
                        to_light = wp.dot(s.p + ls.wi * ls.dist - origin, ls.wi)
                        w = float(1.0)
                        if not ls.delta:
                            w = power_heuristic(ls.pdf, fb.pdf)
                        out.shadow.on = True
                        out.shadow.o = origin
                        out.shadow.d = ls.wi
                        out.shadow.t_max = to_light * (1.0 - 1.0e-4) - ray_epsilon(s.p)
                        out.shadow.L = wp.cw_mul(st.beta, wp.cw_mul(f, ls.L)) * (w / ls.pdf)

        # continue the path by sampling the BSDF
        out.path = st
        if wp.static(light_only):
            return out
        bs = sample_bsdf(b, wo_l, u_bsdf)
        if bs.pdf <= 0.0:
            return out
        st.beta = wp.cw_mul(st.beta, bs.weight)
        if bs.eta > 0.0:
            st.eta_scale = st.eta_scale * bs.eta * bs.eta
        wi = wp.normalize(to_world(frame, bs.wi))
        if wp.dot(wi, s.ng) * bs.wi[2] <= 0.0:
            return out  # the sample crossed the geometric surface on the wrong side (shading-normal leak)
        passing = False
        if wp.static(thin_slabs):
            # through a thin slab's face the path keeps the last vertex's MIS terms: the light it
            # finds beyond is the shadow ray's too (renderer.integrators.thin_slab)
            passing = crosses_thin_slab(scene.mat, m, bs.flags)
        if not passing:
            st.prev_pdf = bs.pdf
            st.prev_specular = (bs.flags & SPECULAR) != 0
            st.prev_p = s.p
        st.o = offset_origin(s, wi)
        st.d = wi
        st.depth = st.depth + 1
        if rr_depth >= 0 and st.depth >= rr_depth:
            mb = max3(st.beta) * st.eta_scale
            if wp.static(media):
                mb = mb / rr_mean       # roulette on the throughput over the channels' mean density
            if mb < 1.0:
                q = wp.max(0.0, 1.0 - mb)
                if u_rr < q:
                    return out
                st.beta = st.beta / (1.0 - q)
        out.path = st
        out.alive = True
        return out

    return scatter


@wp.struct
class ProbeDraws:
    """The subsurface step's first two numbers at a vertex: the wavelength's and its seed."""

    u_lambda: float
    seed: int


@lru_cache(maxsize=None)
def probe_draws(independent: bool) -> wp.Function:
    """``draws(smp, ps, path) -> ProbeDraws``: ``scatter``'s first two draws, the same numbers."""

    @wp.func(inline=True)
    def draws(smp: SamplerParams, ps: PixelSample, path: PathState) -> ProbeDraws:
        d = ProbeDraws()
        if wp.static(independent):
            rng = path.rng
            d.u_lambda = wp.randf(rng)
            d.seed = wp.randi(rng)
        else:
            dim = DIM_BOUNCE + path.depth * DIMS_PER_BOUNCE
            d.u_lambda = get_1d(smp, ps, dim + WAVELENGTH)
            d.seed = int(hashed_bits(ps, dim + SUBSURFACE))
        return d

    return draws


@lru_cache(maxsize=None)
def probe_function(features: Features, independent: bool, kind: str) -> wp.Function:
    """``probe(scene, smp, ps, path, hit, s, m) -> SubsurfaceStep``: the subsurface step ``scatter``
    takes at a vertex of ``kind`` (``moves_vertex``), with the same material parameters and numbers,
    for the wavefront's probe step, which keeps the probe rays out of the shading kernel."""
    step = subsurface_step(dataclasses.replace(features, materials=(kind,)))
    draws = probe_draws(independent)

    @wp.func(inline=True)
    def probe(scene: Scene, smp: SamplerParams, ps: PixelSample, path: PathState, hit: Hit, s: Surface,
              m: int) -> SubsurfaceStep:
        u = draws(smp, ps, path)
        b = load_bsdf(scene.mat, scene.tex, scene.spectral, scene.spectral_n, m, s)
        b.wavelength_u = u.u_lambda
        return step(scene, b, s, hit.inst, -path.d, u.seed)

    return probe
