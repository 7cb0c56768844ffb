"""Which shading kernels a scene has and which queue a material's vertices go to: one kernel per
material kind, and for thin films a second when some take the layered walk and some do not, so the
walk, rare and register-hungry, stays out of the other films' kernel. Shared by the wavefront's
shading and the AOV pass's steps."""
from __future__ import annotations

import dataclasses
from functools import lru_cache
from typing import NamedTuple

import warp as wp

from renderer.device.scene import Features, Scene
from renderer.integrators.path_state import FIRST_KIND
from renderer.materials import (REGISTRY, coatedconductor, coateddiffuse, conductor, dielectric, disney, kind_id,
                                subsurface, thinfilm)

THINFILM = wp.constant(kind_id(thinfilm.NAME))
#: A thin film's flag for the layered walk (its materials' own shading queue, ``Shader.walk``).
LAYERED = wp.constant(thinfilm.FLAG.layered)

#: Material kinds whose whole shading kernel is over 1 KB of frame in every scene measured (sm_90,
#: docs/gpu.md "The light sample and the BSDF sample apart"): the film's coating optics, the layered
#: walk, Disney's lobes, the film on a subsurface body.
SPLIT_KINDS = frozenset({thinfilm.NAME, disney.NAME, subsurface.NAME, coateddiffuse.NAME, coatedconductor.NAME})
#: Kinds over it only with rough lobes that count multiple scattering (the every-feature scene's).
ROUGH_SPLIT_KINDS = frozenset({conductor.NAME, dielectric.NAME})


class Shader(NamedTuple):
    """One shading kernel and its queue: the materials of ``kind``; for thin films, ``walk`` True
    the ones that take the layered random walk, False the others (kernels without the walk's code)."""

    name: str
    kind: str
    walk: bool


def shaders(features: Features) -> list[Shader]:
    """The shading kernels of a scene of ``features``, in queue order (from FIRST_KIND on): one per
    material kind, two for thin films when some take the layered walk and some do not, so the
    walk, rare and register-hungry, stays out of the other films' kernel."""
    out = []
    for kind in features.materials:
        out.append(Shader(f"shade_{kind}", kind, kind == thinfilm.NAME and features.layered and not features.unlayered))
        if kind == thinfilm.NAME and features.layered and features.unlayered:
            out.append(Shader(f"shade_{kind}_walk", kind, True))
    return out


def shader_features(features: Features, shader: Shader) -> Features:
    """What a shader's kernel compiles: thin films apart from those that walk without the walk, those
    that walk with nothing else (their arithmetic is the same)."""
    if shader.kind != thinfilm.NAME:
        return features
    return dataclasses.replace(features, **({"unlayered": False} if shader.walk else {"layered": False}))


def queues_of_kinds(shader_names: list[str], first: int = FIRST_KIND) -> list[int]:
    """Per material kind id, its first queue (-1: none), for kernels named ``<step>_<kind>[_walk]``
    in queue order (``shaders``) from queue ``first`` on: ``queue_chooser`` sends walking films to
    their second queue."""
    queue_of_kind = [-1] * len(REGISTRY)
    for q, name in enumerate(shader_names):
        k = kind_id(name.split("_", 1)[1].removesuffix("_walk"))
        if queue_of_kind[k] < 0:
            queue_of_kind[k] = first + q
    return queue_of_kind


@lru_cache(maxsize=None)
def queue_chooser(features: Features, first: int = FIRST_KIND) -> wp.Function:
    """``shading_queue(scene, queue_of_kind, m) -> int``: the queue of the shader of material m
    (its kind's; thin films that walk have their own when the scene has both kinds of film), the
    shaders' queues counted from ``first``."""
    walks = [first + q for q, sh in enumerate(shaders(features)) if sh.name.endswith("_walk")]
    walk_queue = walks[0] if walks else -1

    @wp.func
    def shading_queue(scene: Scene, queue_of_kind: wp.array(dtype=int), m: int) -> int:
        kind = scene.mat.kind[m]
        queue = queue_of_kind[kind]
        if wp.static(walk_queue >= 0):
            if kind == THINFILM and (scene.mat.flags[m] & LAYERED) != 0:
                queue = walk_queue
        return queue

    return shading_queue


def split_shading(features: Features, shader: Shader) -> bool:
    """Whether the wavefront shades a vertex of ``shader`` in two kernels over its queue, the light
    sample (``light_name``) and then the BSDF sample (``Shader.name``), so neither holds the other's
    lobes and the light sampler: in scenes that sample lights, for the kinds whose one kernel spills
    past the 1 KB frame (``SPLIT_KINDS``; ``ROUGH_SPLIT_KINDS`` with rough lobes that count multiple
    scattering). The others fit whole, and a split costs a second load of the material and a launch."""
    heavy = shader.kind in SPLIT_KINDS or (shader.kind in ROUGH_SPLIT_KINDS and features.multiscatter
                                           and shader.kind not in features.smooth)
    return heavy and features.nee and len(features.lights) > 0


def light_name(shader: Shader) -> str:
    """The name of a split shader's light-sample kernel: ``light_<kind>[_walk]``."""
    return "light_" + shader.name.removeprefix("shade_")
