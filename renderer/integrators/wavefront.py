"""The wavefront integrator (pbrt-v4's GPU design): the megakernel's path loop cut into small
kernels that each do one step for every path of a launch, with the paths' state in memory
(:class:`renderer.integrators.path_state.PathBuffers`) between them.

Per launch: ``start`` (camera rays, the sampler's start), then per depth ``intersect`` (closest
hits), ``hits`` (light that escaped or was hit, the end at the maximum depth, mixes resolved to
the material that shades), ``bump`` in scenes with bump maps (the bump-mapped shading normal of
the paths whose material has one, so the shading kernels hold no texture program for it), one
``shade_<kind>`` per material kind of the scene (a vertex of that kind: its BSDF, dispersion,
the light sample's shadow ray and the BSDF sample that continues the path; for the kinds whose one
kernel spills past 1 KB (``split_shading``) two kernels over its queue, ``light_<kind>`` the light
sample and then ``shade_<kind>`` the BSDF sample, so neither holds the other's code), each after a
``probe_<kind>`` for the kinds whose vertex subsurface scattering may move (the subsurface step
and its probe rays through the BVH, so the shading kernel holds no BVH traversal; before it
``entry_subsurface`` where a film coats a subsurface body: renderer.integrators.film_entry),
``shadow`` (the shadow rays, and what they let through) and ``lenses`` in scenes with thin slabs
(the shadow rays that meet only thin slabs' faces, traced face by face), until no path goes on;
then ``finish`` (the film, dropped samples and ray counts as the megakernel writes them).

Each step calls the functions the megakernel calls (:mod:`renderer.integrators.vertex`), in the
same order per path, so the CPU image is the megakernel's bit for bit. A kernel holds only its
step: on a GPU the BVH query, the light sampling and each material's code no longer share one
thread's registers. Every kernel after ``start`` runs over a queue of path indices (pbrt-v4's
ray queues): ``hits`` pushes each path that goes on into its material kind's queue, so a GPU warp
shades one material; shading pushes the paths that go on and the shadow rays into theirs, so
finished paths cost no thread. The order within a queue does not matter, as every path's result
is its own."""
from __future__ import annotations

import dataclasses
from functools import lru_cache

import warp as wp

from renderer.device.kernel_options import GPU_LAUNCH_BOUNDS, KERNEL_OPTIONS
from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import surface_at
from renderer.geometry.offsets import offset_origin
from renderer.integrators.film_entry import entered_probe, film_entry, film_entry_step
from renderer.integrators.media_path import crossed, is_interface, media_functions, scattered_path, start_medium
from renderer.integrators.path_state import (ARRIVED, BUMPS, FIRST_KIND, LENSES, RAYS, REDIRECTED, SHADOWS,
                                             PathBuffers, load_path, path_buffers, push, push_shadow, store_path,
                                             store_scattered)
from renderer.integrators.shader_queues import (Shader, light_name, queue_chooser, queues_of_kinds, shader_features,
                                                shaders, split_shading)
from renderer.integrators.shading import bump_normal
from renderer.integrators.thin_slab import SLABS_ONLY, crossing, crossing_transmittance, face_walk
from renderer.integrators.subsurface import DISNEY, SUBSURFACE, Exit, exit_of
from renderer.integrators.vertex import (BSDF_SAMPLE, LIGHT_SAMPLE, WHOLE, moves_vertex, path_functions,
                                        probe_function, scatter_function)
from renderer.integrators.visibility import ray_queries
from renderer.media.tracking import ABSORBED, SCATTERED, delta_track
from renderer.sampling.samplers import PixelSample, SamplerParams
from renderer.vecmath import max3, mean3

def step_kernel(f) -> wp.Kernel:
    """A render kernel in a module of its own (compiled, cached and measured alone), held to 128
    registers on CUDA: what does not fit spills into its frame, the figure docs/gpu.md measures
    (uncapped, alpha cut-outs took the every-feature intersection kernel to 163 registers)."""
    return wp.kernel(f, module="unique", module_options=KERNEL_OPTIONS, launch_bounds=GPU_LAUNCH_BOUNDS)


@lru_cache(maxsize=None)
def start_kernel(features: Features, independent: bool) -> wp.Kernel:
    start = path_functions(features, independent).start
    media = features.media

    def start_paths(scene: Scene, smp: SamplerParams, seed: int, sample_index: int, row_offset: int,
                    paths: PathBuffers):
        i = wp.tid()
        pixel = row_offset * scene.cam.width + i
        begun = start(scene, smp, seed, sample_index, pixel)
        store_path(paths, i, begun.path)
        if wp.static(not independent):
            paths.sample[i] = begun.sample
        if wp.static(media):
            paths.media[i] = start_medium(scene, seed, sample_index, pixel)
        paths.queue[RAYS, i] = i        # every path traces its camera ray (the host knows the count)

    return step_kernel(start_paths)


@lru_cache(maxsize=None)
def intersect_kernel(features: Features) -> wp.Kernel:
    closest = ray_queries(features).closest

    def intersect(scene: Scene, paths: PathBuffers):
        i = paths.queue[RAYS, wp.tid()]
        paths.hit[i] = closest(scene, paths.o[i], paths.d[i], 1.0e30)
        paths.rays[i] = paths.rays[i] + 1

    return step_kernel(intersect)


@lru_cache(maxsize=None)
def hits_kernel(features: Features) -> wp.Kernel:
    arrive = path_functions(features, False).arrive     # does not draw numbers: one variant serves both

    bump = features.bump
    shading_queue = queue_chooser(features)
    media = features.media
    arrivals = ARRIVED if media else RAYS       # with media, the rays the medium step let through

    def hits(scene: Scene, paths: PathBuffers, max_depth: int):
        i = paths.queue[arrivals, wp.tid()]
        st = load_path(paths, i)
        hit = paths.hit[i]
        if wp.static(media):
            st.beta = st.beta / mean3(paths.media[i].r_u)   # light found now, over the channels' mean density
        ar = arrive(scene, st, hit, max_depth)
        paths.L[i] = ar.path.L
        if wp.static(media):
            if hit.inst >= 0:
                shape = scene.geo.inst_shape[hit.inst]
                if is_interface(scene, shape):      # a boundary between media: crossed, no bounce
                    s = surface_at(scene.geo, hit, scene.shape_flip[shape] != 0)
                    ms = paths.media[i]
                    ms.medium = crossed(scene, shape, s.ng, st.d, ms.medium)
                    paths.media[i] = ms
                    paths.o[i] = offset_origin(s, st.d)
                    push(paths, REDIRECTED, i)
                    return
        if ar.shade:
            paths.material[i] = ar.m
            push(paths, shading_queue(scene, paths.queue_of_kind, ar.m), i)
            if wp.static(bump):
                if scene.mat.bump[ar.m] >= 0:
                    push(paths, BUMPS, i)

    return step_kernel(hits)


@lru_cache(maxsize=None)
def medium_kernel(features: Features) -> wp.Kernel:
    """The media step (scenes with media, after ``intersect``): the path's next event in its medium
    before the surface it hit (delta tracking, renderer.media.tracking). Absorbed, the path ends;
    scattered, it samples a light and a phase-sampled direction, its next ray traced without
    shading; otherwise it goes on to ``hits``. The megakernel's loop does the same, in this order."""
    scatter_in_medium = media_functions(features).scatter

    def medium(scene: Scene, paths: PathBuffers, max_depth: int):
        i = paths.queue[RAYS, wp.tid()]
        ms = paths.media[i]
        if ms.medium < 0:
            push(paths, ARRIVED, i)
            return
        st = load_path(paths, i)
        hit = paths.hit[i]
        t_hit = float(1.0e30)
        if hit.inst >= 0:
            t_hit = hit.t
        tr = delta_track(scene.media[0], ms.medium, st.o, st.d, t_hit, ms.c, ms.rng, st.beta, ms.r_u, st.L,
                         st.depth < max_depth)
        ms.rng = tr.rng
        st.beta = tr.beta
        ms.r_u = tr.r_u
        st.L = tr.L
        if tr.event == SCATTERED and st.depth < max_depth:
            st.depth = st.depth + 1
            sm = scatter_in_medium(scene, tr.p, -st.d, ms.medium, ms.c, ms.rng, st.beta, ms.r_u)
            ms.rng = sm.rng
            st = scattered_path(st, tr.p, sm)
            push(paths, REDIRECTED, i)
        elif tr.event != ABSORBED and tr.event != SCATTERED:
            push(paths, ARRIVED, i)
        store_path(paths, i, st)
        paths.media[i] = ms

    return step_kernel(medium)


@lru_cache(maxsize=None)
def bump_kernel(features: Features) -> wp.Kernel:
    """The bump step: for every path whose material has a bump map, its bump-mapped shading normal
    (the megakernel's ``bump_normal`` at the same surface: where the probe step left a vertex that
    subsurface scattering moved), kept for its shading kernel."""

    probes = features.subsurface

    def bump(scene: Scene, paths: PathBuffers):
        i = paths.queue[BUMPS, wp.tid()]
        hit = paths.hit[i]
        if wp.static(probes):       # where the probe step moved the vertex (it runs first)
            kind = scene.mat.kind[paths.material[i]]
            if kind == DISNEY or kind == SUBSURFACE:
                if paths.exit[i].hit.inst >= 0:
                    hit = paths.exit[i].hit
        s = surface_at(scene.geo, hit, scene.shape_flip[scene.geo.inst_shape[hit.inst]] != 0)
        paths.ns[i] = bump_normal(scene, scene.mat.bump[paths.material[i]], s, s.ns)

    return step_kernel(bump)


@lru_cache(maxsize=None)
def shade_kernel(features: Features, independent: bool, shader: Shader, part: str = WHOLE) -> wp.Kernel:
    """A shader's vertex (``WHOLE``), or one part of it (``scatter_function``'s ``part``):
    ``LIGHT_SAMPLE`` (``light_<kind>``: the light sample's shadow ray, with media the medium it
    starts in; the path is not stored) or ``BSDF_SAMPLE`` (the path's next ray, its medium,
    roulette), the light part's kernel launched first over the same queue, on the path state both load."""
    kind = shader.kind
    probed = moves_vertex(features, kind)       # the probe step moved its vertex
    bumped = features.bump                      # its normal from the bump step (where the probe left it)
    scatter = scatter_function(shader_features(features, shader), independent, kind, bumped, probed, part)
    queue = FIRST_KIND + shaders(features).index(shader)
    media = features.media
    lights = part != BSDF_SAMPLE
    continues = part != LIGHT_SAMPLE

    def shade(scene: Scene, smp: SamplerParams, paths: PathBuffers, rr_depth: int):
        i = paths.queue[queue, wp.tid()]
        hit = paths.hit[i]
        m = paths.material[i]
        s = surface_at(scene.geo, hit, scene.shape_flip[scene.geo.inst_shape[hit.inst]] != 0)
        if wp.static(bumped):
            if scene.mat.bump[m] >= 0:
                s.ns = paths.ns[i]
        ps = PixelSample()
        if wp.static(not independent):
            ps = paths.sample[i]
        rr_mean = float(1.0)            # with media, roulette weighs the channels' mean density
        if wp.static(media and continues):
            rr_mean = mean3(paths.media[i].r_u)
        moved = Exit()
        if wp.static(probed):
            moved = paths.exit[i]
        sc = scatter(scene, smp, ps, load_path(paths, i), hit, s, m, rr_depth, rr_mean, moved)
        if wp.static(continues):
            store_scattered(paths, i, sc.path)
        if sc.shadow.on:
            push_shadow(paths, i, sc.shadow)
        if wp.static(media):            # which side of the surface the shadow ray and the path leave by
            ms = paths.media[i]
            shape = scene.geo.inst_shape[hit.inst]
            if wp.static(lights):
                if sc.shadow.on:
                    paths.shadow_medium[i] = crossed(scene, shape, sc.ng, sc.shadow.d, ms.medium)
            if sc.alive:
                ms.medium = crossed(scene, shape, sc.ng, sc.path.d, ms.medium)
                paths.media[i] = ms
        if sc.alive:
            push(paths, RAYS, i)

    return step_kernel(shade)


@lru_cache(maxsize=None)
def probe_kernel(features: Features, independent: bool, shader: Shader) -> wp.Kernel:
    """The probe step of a kind whose vertex subsurface scattering may move (``moves_vertex``), before
    its shading kernel, over the same queue: the subsurface step (its probe rays through the BVH),
    its weight and rays applied to the path, and where it left the vertex kept for shading (a film's
    entry on the body from ``entry_kernel``, run before it: renderer.integrators.film_entry)."""
    entered = film_entry_step(features, shader.kind)
    probe = entered_probe(independent) if entered else probe_function(features, independent, shader.kind)
    queue = FIRST_KIND + shaders(features).index(shader)

    def probe_paths(scene: Scene, smp: SamplerParams, paths: PathBuffers):
        i = paths.queue[queue, wp.tid()]
        hit = paths.hit[i]
        s = surface_at(scene.geo, hit, scene.shape_flip[scene.geo.inst_shape[hit.inst]] != 0)
        ps = PixelSample()
        if wp.static(not independent):
            ps = paths.sample[i]
        if wp.static(entered):
            ev = probe(scene, smp, ps, load_path(paths, i), hit, s, paths.material[i], paths.entry[i])
        else:
            ev = probe(scene, smp, ps, load_path(paths, i), hit, s, paths.material[i])
        paths.beta[i] = wp.cw_mul(paths.beta[i], ev.weight)
        paths.rays[i] = paths.rays[i] + ev.rays
        paths.exit[i] = exit_of(ev)

    return step_kernel(probe_paths)


@lru_cache(maxsize=None)
def entry_kernel(features: Features, independent: bool, shader: Shader) -> wp.Kernel:
    """A film's entry on the coated bodies of the probe step's queue, before it (renderer.integrators.film_entry)."""
    entry = film_entry(independent)
    queue = FIRST_KIND + shaders(features).index(shader)

    def entry_paths(scene: Scene, smp: SamplerParams, paths: PathBuffers):
        entry(scene, smp, paths, paths.queue[queue, wp.tid()])

    return step_kernel(entry_paths)


def lens_step(features: Features) -> bool:
    """Whether shadow rays that meet thin slabs' faces go to a kernel of their own (``lenses``):
    with alpha cut-outs every such shadow ray walks its hits in ``shadow``, as alpha needs."""
    return features.thin_slabs and not features.alpha and not features.media


@lru_cache(maxsize=None)
def shadow_kernel(features: Features) -> wp.Kernel:
    blocked, transmitted = ray_queries(features)[1:]
    thin_slabs = features.thin_slabs
    lenses = lens_step(features)
    media = features.media
    through_media = media_functions(features).shadow

    def shadow(scene: Scene, paths: PathBuffers):
        i = paths.queue[SHADOWS, wp.tid()]
        paths.rays[i] = paths.rays[i] + 1
        if wp.static(media):            # transmittance through media and interfaces
            ms = paths.media[i]
            tm = through_media(scene, paths.shadow_o[i], paths.shadow_d[i], paths.shadow_t[i], paths.shadow_medium[i],
                               ms.c, ms.rng)
            ms.rng = tm.rng
            paths.media[i] = ms
            if max3(tm.T) > 0.0:
                paths.L[i] = paths.L[i] + wp.cw_mul(paths.shadow_L[i], tm.T) / mean3(wp.cw_mul(ms.r_u, tm.r))
        elif wp.static(lenses):           # the rays past a lens to the lens step (renderer.integrators.thin_slab)
            c = crossing(scene, paths.shadow_o[i], paths.shadow_d[i], paths.shadow_t[i])
            if c == SLABS_ONLY:
                push(paths, LENSES, i)
            else:
                paths.L[i] = paths.L[i] + wp.cw_mul(paths.shadow_L[i], crossing_transmittance(c))
        elif wp.static(thin_slabs):
            paths.L[i] = paths.L[i] + wp.cw_mul(paths.shadow_L[i], transmitted(scene, paths.shadow_o[i],
                                                                               paths.shadow_d[i], paths.shadow_t[i]))
        elif not blocked(scene, paths.shadow_o[i], paths.shadow_d[i], paths.shadow_t[i]):
            paths.L[i] = paths.L[i] + paths.shadow_L[i]

    return step_kernel(shadow)


@lru_cache(maxsize=None)
def lens_kernel(features: Features) -> wp.Kernel:
    """The lens step: shadow rays that meet only thin slabs' faces, traced face by face (the
    megakernel's ``transmitted`` past its any-hit pass), off the ordinary shadow kernel."""
    through_faces = face_walk(ray_queries(features).closest, own_kernel=True)

    def lenses(scene: Scene, paths: PathBuffers):
        i = paths.queue[LENSES, wp.tid()]
        paths.L[i] = paths.L[i] + wp.cw_mul(paths.shadow_L[i], through_faces(scene, paths.shadow_o[i],
                                                                             paths.shadow_d[i], paths.shadow_t[i]))

    return step_kernel(lenses)


@lru_cache(maxsize=None)
def finish_kernel(features: Features) -> wp.Kernel:
    record = path_functions(features, False).record

    def finish(scene: Scene, paths: PathBuffers, row_offset: int, film: wp.array(dtype=wp.vec3d),
               bad_samples: wp.array(dtype=int), ray_count: wp.array(dtype=wp.int64)):
        i = wp.tid()
        record(scene, load_path(paths, i), row_offset * scene.cam.width + i, film, bad_samples, ray_count)

    return step_kernel(finish)


def wavefront_kernels(features: Features, independent: bool) -> dict[str, wp.Kernel]:
    """By name, in launch order: the kernels of one wavefront pass for a scene of ``features``."""
    kernels = {"start": start_kernel(features, independent), "intersect": intersect_kernel(features)}
    if features.media:
        kernels["medium"] = medium_kernel(features)
    kernels["hits"] = hits_kernel(features)
    if features.bump:
        kernels["bump"] = bump_kernel(features)
    for shader in shaders(features):
        if film_entry_step(features, shader.kind):
            kernels[f"entry_{shader.kind}"] = entry_kernel(features, independent, shader)
        if moves_vertex(features, shader.kind):
            kernels[f"probe_{shader.kind}"] = probe_kernel(features, independent, shader)
        if split_shading(features, shader):
            kernels[light_name(shader)] = shade_kernel(features, independent, shader, LIGHT_SAMPLE)
            kernels[shader.name] = shade_kernel(features, independent, shader, BSDF_SAMPLE)
        else:
            kernels[shader.name] = shade_kernel(features, independent, shader)
    kernels["shadow"] = shadow_kernel(features)
    if lens_step(features):
        kernels["lenses"] = lens_kernel(features)
    kernels["finish"] = finish_kernel(features)
    return kernels


@dataclasses.dataclass
class Wavefront:
    """Runs wavefront passes over row chunks: one set of path buffers per worker (``slots``), each
    sized to the largest chunk (``max_paths``)."""

    kernels: dict[str, wp.Kernel]
    independent: bool
    max_paths: int
    slots: int
    device: str

    def __post_init__(self) -> None:
        names = [name for name in self.kernels if name.startswith("shade_")]     # in queue order (``shaders``)
        probed = any(name.startswith("probe_") for name in self.kernels)
        self.buffers = [path_buffers(self.max_paths, not self.independent, queues_of_kinds(names), len(names),
                                     self.device, "bump" in self.kernels, "medium" in self.kernels, probed,
                                     any(name.startswith("entry_") for name in self.kernels))
                        for _ in range(self.slots)]
        self.shaders = [self.kernels[name] for name in names]
        # per shading kernel its probe step's kernels (a film's entry, the probe), run first over the same queue
        self.probes = [[self.kernels[step + name.removeprefix("shade_")] for step in ("entry_", "probe_")
                        if step + name.removeprefix("shade_") in self.kernels] for name in names]
        # per shading kernel its light part's kernel, run before it over the same queue (None: one kernel)
        self.lights = [self.kernels.get("light_" + name.removeprefix("shade_")) for name in names]

    def launch(self, slot: int, scene: Scene, smp: SamplerParams, seed: int, sample_index: int, first_row: int,
               rows: int, max_depth: int, rr_depth: int, film: wp.array, bad_samples: wp.array,
               ray_count: wp.array) -> None:
        """One sample for every pixel of rows ``first_row ...``, added as the megakernel adds it.
        Every kernel after ``start`` runs over a queue, whose length the host reads (twice per
        depth: after ``hits``, the shading queues; after shading, the rays and shadow rays to
        trace); the loop ends when no path is left to trace, by ``max_depth`` at the latest. The probe
        steps (a film's entry, then the probe) run first, then the bump step (where the probes left
        the vertices), then the shading kernels (a split shader's light sample before its BSDF
        sample, which advances the path); the lens step after the shadow kernel; with media the
        medium step runs between ``intersect`` and ``hits`` (one more read of a queue's length), and
        the paths it or ``hits`` redirected join the rays that shading continues."""
        k, paths, dev = self.kernels, self.buffers[slot], self.device
        n = rows * scene.cam.width
        wp.launch(k["start"], dim=n, inputs=[scene, smp, seed, sample_index, first_row, paths], device=dev)
        tracing = n
        while tracing > 0:
            wp.launch(k["intersect"], dim=tracing, inputs=[scene, paths], device=dev)
            paths.queued.zero_()
            arrived = tracing
            if "medium" in k:
                wp.launch(k["medium"], dim=tracing, inputs=[scene, paths, max_depth], device=dev)
                arrived = int(paths.queued.numpy()[ARRIVED])
            if arrived > 0:
                wp.launch(k["hits"], dim=arrived, inputs=[scene, paths, max_depth], device=dev)
            queued = paths.queued.numpy().copy()
            paths.queued.zero_()
            for probes, count in zip(self.probes, queued[FIRST_KIND:]):
                for probe in probes if count > 0 else ():
                    wp.launch(probe, dim=int(count), inputs=[scene, smp, paths], device=dev)
            if queued[BUMPS] > 0:
                wp.launch(k["bump"], dim=int(queued[BUMPS]), inputs=[scene, paths], device=dev)
            for light, shade, count in zip(self.lights, self.shaders, queued[FIRST_KIND:]):
                for kernel in (light, shade):
                    if kernel is not None and count > 0:
                        wp.launch(kernel, dim=int(count), inputs=[scene, smp, paths, rr_depth], device=dev)
            redirected = int(queued[REDIRECTED])
            queued = paths.queued.numpy()
            tracing, shadows = int(queued[RAYS]), int(queued[SHADOWS])
            if redirected > 0:          # media: traced next beside the rays shading continued
                wp.copy(paths.queue[RAYS], paths.queue[REDIRECTED], dest_offset=tracing, count=redirected)
                tracing += redirected
            if shadows > 0:
                wp.launch(k["shadow"], dim=shadows, inputs=[scene, paths], device=dev)
                lenses = int(paths.queued.numpy()[LENSES]) if "lenses" in k else 0
                if lenses > 0:
                    wp.launch(k["lenses"], dim=lenses, inputs=[scene, paths], device=dev)
        wp.launch(k["finish"], dim=n, inputs=[scene, paths, first_row, film, bad_samples, ray_count], device=dev)
