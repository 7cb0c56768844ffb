"""A film's entry on pbrt-v4's ``subsurface`` material as a wavefront step of its own: where a
film or stack coats the body, the probability q of entering and the refracted sample's weight
(:func:`renderer.integrators.tabulated_subsurface.tabulated_scatter`'s ``entry``) call the
coating's out-of-line optics at six sites, each spilling every value the probe step keeps live
across it. The ``entry_subsurface`` kernel computes them before the probe step, which reads them
(docs/gpu.md, "The tabulated subsurface probe"); the numbers drawn are the step's own, so the
paths are the megakernel's bit for bit."""
from __future__ import annotations

from functools import lru_cache

import warp as wp

from renderer.device.scene import Features, Scene
from renderer.geometry.intersect import Hit, Surface, surface_at
from renderer.integrators.path_state import PathBuffers, PathState, load_path
from renderer.integrators.shading import load_bsdf
from renderer.integrators.subsurface import SubsurfaceStep
from renderer.integrators.tabulated_subsurface import Entry, tabulated_scatter
from renderer.integrators.vertex import probe_draws
from renderer.materials import subsurface
from renderer.sampling.samplers import PixelSample, SamplerParams


def film_entry_step(features: Features, kind: str) -> bool:
    """Whether the probe step of ``kind`` takes a film's entry from a step of its own."""
    return features.subsurface and features.coated_body and kind == subsurface.NAME


@lru_cache(maxsize=None)
def film_entry(independent: bool) -> wp.Function:
    """``entry(scene, smp, paths, i)``: where path ``i``'s body is coated, the film's entry weight
    (xyz) and q (w) at its vertex into ``paths.entry``."""
    draws = probe_draws(independent)
    coated = tabulated_scatter(True)

    @wp.func
    def entry(scene: Scene, smp: SamplerParams, paths: PathBuffers, i: int):
        m = paths.material[i]
        if (scene.mat.flags[m] & subsurface.FILM) != 0:
            hit = paths.hit[i]
            s = surface_at(scene.geo, hit, scene.shape_flip[scene.geo.inst_shape[hit.inst]] != 0)
            ps = PixelSample()
            if wp.static(not independent):
                ps = paths.sample[i]
            path = load_path(paths, i)
            u = draws(smp, ps, path)
            b = load_bsdf(scene.mat, scene.tex, scene.spectral, scene.spectral_n, m, s)
            b.wavelength_u = u.u_lambda
            arrival = wp.static(coated.entry)(b, s, -path.d, u.seed)
            paths.entry[i] = wp.vec4(arrival.weight[0], arrival.weight[1], arrival.weight[2], arrival.q)

    return entry


@lru_cache(maxsize=None)
def entered_probe(independent: bool) -> wp.Function:
    """``probe(scene, smp, ps, path, hit, s, m, film) -> SubsurfaceStep``: the probe step of
    :func:`renderer.integrators.vertex.probe_function` with a coated body's entry given (``film``,
    from :func:`film_entry`); a bare body's is computed here (no coating optics)."""
    draws = probe_draws(independent)
    coated = tabulated_scatter(True)
    bare = tabulated_scatter(False)

    @wp.func
    def probe(scene: Scene, smp: SamplerParams, ps: PixelSample, path: PathState, hit: Hit, s: Surface, m: int,
              film: wp.vec4) -> SubsurfaceStep:
        u = draws(smp, ps, path)
        b = load_bsdf(scene.mat, scene.tex, scene.spectral, scene.spectral_n, m, s)
        b.wavelength_u = u.u_lambda
        arrival = Entry()
        if (b.flags & subsurface.FILM) != 0:
            arrival.q = film[3]
            arrival.weight = wp.vec3(film[0], film[1], film[2])
        else:
            arrival = wp.static(bare.entry)(b, s, -path.d, u.seed)
        return wp.static(coated.entered)(scene, b, s, hit.inst, -path.d, u.seed, arrival)

    return probe
