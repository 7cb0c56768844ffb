"""The path-tracing megakernel: one thread per pixel, a bounded path loop, next-event estimation
with MIS against BSDF sampling, and Russian roulette.

``integrator_kernel(features, independent)`` builds (once per distinct :class:`Features`) a kernel
that only contains the material types, light types and bump mapping the scene uses, so a
diffuse-only scene compiles and runs the same code however many materials the renderer learns.
With ``independent`` the path draws its numbers in order from one RNG stream (the independent
sampler); otherwise every use asks the scene's sampler for its own dimension in the order
``renderer.sampling.samplers`` documents.
"""
from __future__ import annotations

from functools import lru_cache

import warp as wp

from renderer.camera import generate_ray
from renderer.device.kernel_options import KERNEL_OPTIONS
from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import surface_at
from renderer.geometry.offsets import offset_origin, ray_epsilon
from renderer.integrators.emission import emitted_adder, escaped_adder
from renderer.integrators.media_path import crossed, is_interface, media_functions, start_medium
from renderer.integrators.shading import load_bsdf, shading_functions
from renderer.integrators.subsurface import subsurface_step
from renderer.integrators.visibility import ray_queries
from renderer.lights import dispatch
from renderer.lights.sample import light_sampler
from renderer.materials import dielectric, kind_id
from renderer.materials.bsdf import SPECULAR
from renderer.materials.selection import choose_material
from renderer.media.tracking import ABSORBED, SCATTERED, delta_track, mean3
from renderer.optics.dispersion import sample_wavelength, wavelength_weight
from renderer.pixel_filter import sample_filter
from renderer.sampling.frames import to_local, to_world
from renderer.sampling.mis import power_heuristic
from renderer.sampling.rng import sample_rng
from renderer.sampling.samplers import (BSDF, DIM_BOUNCE, DIM_LENS, DIMS_PER_BOUNCE, LIGHT, LIGHT_CHOICE, LOBE,
                                        ROULETTE, SUBSURFACE, WAVELENGTH, SamplerParams, get_1d, get_2d,
                                        get_pixel_2d, hashed_bits, start_sample)
from renderer.sensor import film_value
from renderer.vecmath import max3

#: The kind id of dielectrics, the material that may disperse.
DIELECTRIC = wp.constant(kind_id(dielectric.NAME))


@lru_cache(maxsize=None)
def integrator_kernel(features: Features, independent: bool = False) -> wp.Kernel:
    shading_frame, eval_pdf, sample_bsdf = shading_functions(features)
    nee = features.nee
    add_escaped = escaped_adder(*dispatch(features.escaping, "escaped"), nee)   # lights rays leaving the scene see
    emitters, emitter_ids = dispatch(features.lights, "emitted")              # lights on surfaces
    add_emitted = emitted_adder(emitters, emitter_ids, nee)
    sample_light = light_sampler(*dispatch(features.lights, "sample"))
    light_sampling = nee and len(features.lights) > 0
    has_sss = features.subsurface
    subsurface_scatter = subsurface_step(features)
    closest, blocked = ray_queries(features)
    mixes = features.mix
    dispersion = features.dispersion
    media = features.media                  # volpath's media (renderer.integrators.media_path)
    shadow, scatter_in_medium = media_functions(features).shadow, media_functions(features).scatter

    @wp.kernel(module="unique", module_options=KERNEL_OPTIONS)
    def integrate(scene: Scene, smp: SamplerParams, seed: int, sample_index: int, row_offset: int, max_depth: int,
                  rr_depth: int,
                  film: wp.array(dtype=wp.vec3d), bad_samples: wp.array(dtype=int),
                  ray_count: wp.array(dtype=wp.int64)):
        tid = wp.tid()
        width = scene.cam.width
        pixel = row_offset * width + tid
        px = pixel % width
        py = pixel // width
        n_lights = scene.lights.count
        sel = 1.0 / float(wp.max(n_lights, 1))
        n_rays = int(0)
        rng = sample_rng(seed, sample_index, pixel)
        if wp.static(independent):
            jit = wp.vec2(wp.randf(rng), wp.randf(rng))  # drawn inline: Warp passes rng by value
            u_lens = wp.vec2(wp.randf(rng), wp.randf(rng))
        else:
            ps = start_sample(smp, seed, pixel, px, py, sample_index)
            jit = get_pixel_2d(smp, ps)
            u_lens = get_2d(smp, ps, DIM_LENS)
        fs = sample_filter(scene.cam.filter, jit)      # the pixel filter's offset and weight
        ray = generate_ray(scene.cam, float(px) + fs.p[0], float(py) + fs.p[1], u_lens)
        o = ray.o
        d = ray.d
        L = wp.vec3(0.0)
        beta = wp.vec3(1.0)
        eta_scale = float(1.0)  # undoes the 1/eta^2 radiance scaling for Russian roulette
        prev_pdf = float(0.0)
        prev_specular = bool(True)
        prev_p = o
        depth = int(0)
        hero = float(0.0)       # the path's wavelength (nm) once it met a dispersive dielectric; 0: none yet
        if wp.static(media):
            ms = start_medium(scene, seed, sample_index, pixel)
        while True:
            hit = closest(scene, o, d, 1.0e30)
            n_rays += 1
            beta_l = beta           # what light found now is weighted by (media: over the channels' mean)
            if wp.static(media):
                # media: the next event before the surface (renderer.media.tracking)
                if ms.medium >= 0:
                    t_hit = float(1.0e30)
                    if hit.inst >= 0:
                        t_hit = hit.t
                    tr = delta_track(scene.media, ms.medium, o, d, t_hit, ms.c, ms.rng, beta, ms.r_u, L,
                                     depth < max_depth)
                    ms.rng = tr.rng
                    beta = tr.beta
                    ms.r_u = tr.r_u
                    L = tr.L
                    if tr.event == ABSORBED:
                        break
                    if tr.event == SCATTERED:
                        if depth >= max_depth:
                            break
                        depth += 1
                        sc = scatter_in_medium(scene, tr.p, -d, ms.medium, ms.c, ms.rng, beta, ms.r_u)
                        ms.rng = sc.rng
                        L = L + sc.L
                        n_rays += 1
                        prev_pdf = sc.pdf
                        prev_specular = False
                        prev_p = tr.p
                        o = tr.p
                        d = sc.wi
                        continue
                beta_l = beta / mean3(ms.r_u)
            if hit.inst < 0:
                L = add_escaped(scene.lights, o, d, beta_l, sel, prev_pdf, prev_specular, L)
                break
            shape = scene.geo.inst_shape[hit.inst]
            s = surface_at(scene.geo, hit, scene.shape_flip[shape] != 0)
            wo = -d
            if wp.static(len(emitters) > 0):
                li = scene.shape_light[shape]
                if li >= 0:
                    L = add_emitted(scene.lights, li, prev_p, s.p, s.ng, wo, beta_l, sel, prev_pdf, prev_specular, L)
            if wp.static(media):
                if is_interface(scene, shape):      # a boundary between media: cross it, no bounce
                    ms.medium = crossed(scene, shape, s.ng, d, ms.medium)
                    o = offset_origin(s, d)
                    continue
            if depth >= max_depth:
                break
            m = scene.shape_material[shape]
            if wp.static(mixes):
                m = choose_material(scene.mat.kind, scene.mat.mix, scene.tex, m, s, wo)
            b = load_bsdf(scene.mat, scene.tex, scene.spectral, scene.spectral_n, m, s)
            # this bounce's numbers, drawn before any of them is used (the same stream order as ever)
            u_sss = int(0)
            if wp.static(independent):
                b.wavelength_u = wp.randf(rng)
                if wp.static(has_sss):
                    u_sss = wp.randi(rng)
                u_sel = wp.randf(rng)
                u_light = wp.vec2(wp.randf(rng), wp.randf(rng))
                u_bsdf = wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng))
                u_rr = wp.randf(rng)
            else:
                dim = DIM_BOUNCE + depth * DIMS_PER_BOUNCE
                b.wavelength_u = get_1d(smp, ps, dim + WAVELENGTH)
                if wp.static(has_sss):
                    u_sss = int(hashed_bits(ps, dim + SUBSURFACE))
                u_sel = get_1d(smp, ps, dim + LIGHT_CHOICE)
                u_light = get_2d(smp, ps, dim + LIGHT)
                ub = get_2d(smp, ps, dim + BSDF)
                u_bsdf = wp.vec3(ub[0], ub[1], get_1d(smp, ps, dim + LOBE))
                u_rr = get_1d(smp, ps, dim + ROULETTE)
            if wp.static(dispersion):
                # the first dispersive interface picks the path's wavelength (renderer.optics.dispersion)
                if b.kind == DIELECTRIC and b.table_first > 0:
                    if hero == 0.0:
                        hs = sample_wavelength(b.wavelength_u)
                        hero = hs[0]
                        beta = wp.cw_mul(beta, wavelength_weight(scene.spectral, hs))
                    b = dielectric.dispersed(b, hero)
            if wp.static(has_sss):
                # subsurface scattering may move the vertex to where light leaves the object
                sss = subsurface_scatter(scene, b, s, hit.inst, wo, u_sss)
                n_rays += sss.rays
                beta = wp.cw_mul(beta, sss.weight)
                s = sss.s
                b = sss.b
                wo = sss.wo
            frame = shading_frame(scene, m, s)
            wo_l = to_local(frame, wo)

            # next-event estimation: one light, MIS-weighted against BSDF sampling
            if wp.static(light_sampling):
                if n_lights > 0:
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
                            t_max = to_light * (1.0 - 1.0e-4) - ray_epsilon(s.p)
                            n_rays += 1
                            if wp.static(media):
                                # transmittance through media and interfaces (renderer.integrators.media_path)
                                tm = shadow(scene, origin, ls.wi, t_max, crossed(scene, shape, s.ng, ls.wi, ms.medium),
                                            ms.c, ms.rng)
                                ms.rng = tm.rng
                                if max3(tm.T) > 0.0:
                                    w = float(1.0)
                                    if not ls.delta:
                                        w = power_heuristic(ls.pdf, fb.pdf)
                                    L = L + wp.cw_mul(wp.cw_mul(beta, wp.cw_mul(f, ls.L)), tm.T) * (
                                        w / (ls.pdf * mean3(wp.cw_mul(ms.r_u, tm.r))))
                            elif not blocked(scene, origin, ls.wi, t_max):
                                w = float(1.0)
                                if not ls.delta:
                                    w = power_heuristic(ls.pdf, fb.pdf)
                                L = L + wp.cw_mul(beta, wp.cw_mul(f, ls.L)) * (w / ls.pdf)

            # continue the path by sampling the BSDF
            bs = sample_bsdf(b, wo_l, u_bsdf)
            if bs.pdf <= 0.0:
                break
            beta = wp.cw_mul(beta, bs.weight)
            if bs.eta > 0.0:
                eta_scale = eta_scale * bs.eta * bs.eta
            wi = wp.normalize(to_world(frame, bs.wi))
            if wp.dot(wi, s.ng) * bs.wi[2] <= 0.0:
                break  # the sample crossed the geometric surface on the wrong side (shading-normal leak)
            prev_pdf = bs.pdf
            prev_specular = (bs.flags & SPECULAR) != 0
            prev_p = s.p
            o = offset_origin(s, wi)
            d = wi
            depth += 1
            if wp.static(media):
                ms.medium = crossed(scene, shape, s.ng, wi, ms.medium)
            if rr_depth >= 0 and depth >= rr_depth:
                mb = max3(beta) * eta_scale
                if wp.static(media):
                    mb = mb / mean3(ms.r_u)
                if mb < 1.0:
                    q = wp.max(0.0, 1.0 - mb)
                    if u_rr < q:
                        break
                    beta = beta / (1.0 - q)
        # a path through dispersive glass carries one wavelength, whose sRGB may have a negative channel
        if wp.isfinite(L) and (wp.static(dispersion) or (L[0] >= 0.0 and L[1] >= 0.0 and L[2] >= 0.0)):
            film[pixel] = film[pixel] + film_value(scene.cam.sensor, L, fs.weight)
        else:
            wp.atomic_add(bad_samples, py, 1)   # per row: no two CPU threads ever add into one counter
        ray_count[pixel] = ray_count[pixel] + wp.int64(n_rays)   # this thread's pixel alone: no atomic

    return integrate
