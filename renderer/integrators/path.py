"""The path-tracing megakernel: one thread per pixel, a bounded path loop, next-event estimation
with MIS against BSDF sampling, and Russian roulette.

``integrator_kernel(features)`` builds (once per distinct :class:`Features`) a kernel that only
contains the material types, light types and bump mapping the scene uses, so a diffuse-only
scene compiles and runs the same code however many materials the renderer learns.
"""
from __future__ import annotations

from functools import lru_cache

import warp as wp

from renderer.camera import generate_ray
from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import intersect, occluded, surface_at
from renderer.geometry.offsets import offset_origin, ray_epsilon
from renderer.lights import DISTANT, area_emitted, area_pdf, distant_cone_radiance, env_pdf, env_radiance, sample_light
from renderer.materials import dispatch_table
from renderer.materials.bsdf import BSDFSample
from renderer.sampling.frames import frame_from_tangent, to_local, to_world
from renderer.vecmath import max3
from renderer.sampling.mis import power_heuristic
from renderer.sampling.rng import sample_rng
from renderer.integrators.shading import bump_normal, load_bsdf
from renderer.integrators.subsurface import subsurface_scatter


@lru_cache(maxsize=None)
def integrator_kernel(features: Features) -> wp.Kernel:
    mods, kinds = dispatch_table(features.materials)
    n_mat = len(mods)
    has_bump = features.bump
    has_env = features.env
    has_area = features.area
    has_soft = features.soft_distant
    nee = features.nee
    has_sss = features.subsurface

    @wp.kernel(module="unique")
    def integrate(scene: Scene, seed: int, sample_start: int, n_samples: int, row_offset: int, max_depth: int,
                  rr_depth: int,
                  film: wp.array(dtype=wp.vec3d), bad_samples: wp.array(dtype=int),
                  ray_count: wp.array(dtype=wp.float64)):
        tid = wp.tid()
        width = scene.cam.width
        pixel = row_offset * width + tid
        px = pixel % width
        py = pixel // width
        n_lights = scene.lights.count
        sel = 1.0 / float(wp.max(n_lights, 1))
        acc = wp.vec3(0.0)
        n_rays = int(0)
        for k in range(n_samples):
            rng = sample_rng(seed, sample_start + k, pixel)
            jit = wp.vec2(wp.randf(rng), wp.randf(rng))  # not rand2: Warp passes rng by value
            ray = generate_ray(scene.cam, float(px) + jit[0], float(py) + jit[1],
                               wp.vec2(wp.randf(rng), wp.randf(rng)))
            o = ray.o
            d = ray.d
            L = wp.vec3(0.0)
            beta = wp.vec3(1.0)
            eta_scale = float(1.0)  # undoes the 1/eta^2 radiance scaling for Russian roulette
            prev_pdf = float(0.0)
            prev_specular = bool(True)
            prev_p = o
            depth = int(0)
            while True:
                hit = intersect(scene.geo, o, d, 1.0e30)
                n_rays += 1
                if hit.inst < 0:
                    if wp.static(has_env):
                        Le = env_radiance(scene.lights, d)
                        w = float(1.0)
                        if wp.static(nee):
                            if not prev_specular:
                                w = power_heuristic(prev_pdf, env_pdf(scene.lights, d) * sel)
                        L = L + wp.cw_mul(beta, Le) * w
                    if wp.static(has_soft):
                        for i in range(n_lights):
                            if scene.lights.kind[i] == DISTANT:
                                Ld = distant_cone_radiance(scene.lights, i, d)
                                if max3(Ld) > 0.0:
                                    w = float(1.0)
                                    if wp.static(nee):
                                        if not prev_specular:
                                            cm = scene.lights.cos_max[i]
                                            w = power_heuristic(prev_pdf, sel / (6.283185307179586 * (1.0 - cm)))
                                    L = L + wp.cw_mul(beta, Ld) * w
                    break
                shape = scene.geo.inst_shape[hit.inst]
                s = surface_at(scene.geo, hit, scene.shape_flip[shape] != 0)
                wo = -d
                if wp.static(has_area):
                    li = scene.shape_light[shape]
                    if li >= 0:
                        Le = area_emitted(scene.lights, li, s.ng, wo)
                        w = float(1.0)
                        if wp.static(nee):
                            if not prev_specular:
                                w = power_heuristic(prev_pdf, area_pdf(scene.lights, li, prev_p, s.p, s.ng) * sel)
                        L = L + wp.cw_mul(beta, Le) * w
                if depth >= max_depth:
                    break
                m = scene.shape_material[shape]
                b = load_bsdf(scene, m, s.uv)
                b.wavelength_u = wp.randf(rng)
                if wp.static(has_sss):
                    # subsurface scattering may move the vertex to where light leaves the object
                    sss = subsurface_scatter(scene, b, s, hit.inst, wo, wp.randi(rng))
                    n_rays += sss.rays
                    beta = wp.cw_mul(beta, sss.weight)
                    s = sss.s
                    b = sss.b
                    wo = sss.wo
                ns = s.ns
                if wp.static(has_bump):
                    bt = scene.mat.bump[m]
                    if bt >= 0:
                        ns = bump_normal(scene, bt, s.uv, ns, s.dpdu, s.dpdv)
                frame = frame_from_tangent(ns, s.dpdu)
                wo_l = to_local(frame, wo)

                # next-event estimation: one light, MIS-weighted against BSDF sampling
                u_sel = wp.randf(rng)
                u_light = wp.vec2(wp.randf(rng), wp.randf(rng))
                if wp.static(nee):
                    if n_lights > 0:
                        ls = sample_light(scene.lights, s.p, u_sel, u_light)
                        if ls.pdf > 0.0 and max3(ls.L) > 0.0:
                            wi_l = to_local(frame, ls.wi)
                            f = wp.vec3(0.0)
                            pdf_b = float(0.0)
                            for j in range(wp.static(n_mat)):
                                if b.kind == wp.static(kinds[j]):
                                    f = wp.static(mods[j].eval)(b, wo_l, wi_l)
                                    pdf_b = wp.static(mods[j].pdf)(b, wo_l, wi_l)
                            # shading normals must not let light through the geometric surface
                            if wp.dot(ls.wi, s.ng) * wi_l[2] <= 0.0:
                                f = wp.vec3(0.0)
                            f = f * wp.abs(wi_l[2])
                            if max3(f) > 0.0:
                                origin = offset_origin(s, ls.wi)
                                t_max = ls.dist * (1.0 - 1.0e-5) - ray_epsilon(s.p)
                                n_rays += 1
                                if not occluded(scene.geo, origin, ls.wi, t_max):
                                    w = float(1.0)
                                    if not ls.delta:
                                        w = power_heuristic(ls.pdf, pdf_b)
                                    L = L + wp.cw_mul(beta, wp.cw_mul(f, ls.L)) * (w / ls.pdf)

                # continue the path by sampling the BSDF
                u_bsdf = wp.vec3(wp.randf(rng), wp.randf(rng), wp.randf(rng))
                bs = BSDFSample()
                for j in range(wp.static(n_mat)):
                    if b.kind == wp.static(kinds[j]):
                        bs = wp.static(mods[j].sample)(b, wo_l, u_bsdf)
                if bs.pdf <= 0.0:
                    break
                beta = wp.cw_mul(beta, bs.weight)
                if bs.eta > 0.0:
                    eta_scale = eta_scale * bs.eta * bs.eta
                wi = wp.normalize(to_world(frame, bs.wi))
                if wp.dot(wi, s.ng) * bs.wi[2] <= 0.0:
                    break  # the sample crossed the geometric surface on the wrong side (shading-normal leak)
                prev_pdf = bs.pdf
                prev_specular = bs.specular
                prev_p = s.p
                o = offset_origin(s, wi)
                d = wi
                depth += 1
                u_rr = wp.randf(rng)
                if rr_depth >= 0 and depth >= rr_depth:
                    mb = max3(beta) * eta_scale
                    if mb < 1.0:
                        q = wp.max(0.0, 1.0 - mb)
                        if u_rr < q:
                            break
                        beta = beta / (1.0 - q)
            if wp.isfinite(L) and L[0] >= 0.0 and L[1] >= 0.0 and L[2] >= 0.0:
                acc = acc + L
            else:
                wp.atomic_add(bad_samples, 0, 1)
        film[pixel] = film[pixel] + wp.vec3d(wp.float64(acc[0]), wp.float64(acc[1]), wp.float64(acc[2]))
        wp.atomic_add(ray_count, 0, wp.float64(n_rays))

    return integrate
