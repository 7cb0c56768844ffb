"""What a path carries from one vertex to the next, in two forms: :class:`PathState`, the values
one thread holds (the megakernel keeps it in registers across its loop), and :class:`PathBuffers`,
the same values for every path of a launch as one Warp array per field (structure of arrays, so a
wavefront kernel's neighbouring threads read neighbouring words). The wavefront's kernels load a
path's state, advance it with the very functions the megakernel calls
(:mod:`renderer.integrators.vertex`) and store it back: float32 values survive the round trip
through memory exactly, so both integrators compute the same bits."""
from __future__ import annotations

import warp as wp

from renderer.geometry.intersect import Hit
from renderer.integrators.subsurface import Exit
from renderer.sampling.samplers import PixelSample


@wp.struct
class PathState:
    """One path between vertices."""

    o: wp.vec3              # the next ray
    d: wp.vec3
    L: wp.vec3              # radiance gathered so far
    beta: wp.vec3           # throughput
    prev_p: wp.vec3         # the last vertex (area lights' MIS needs it)
    eta_scale: float        # undoes the 1/eta^2 radiance scaling for Russian roulette
    prev_pdf: float         # the BSDF density of the bounce that led here
    prev_specular: bool
    hero: float             # the path's wavelength (nm) once it met a dispersive dielectric; 0: none yet
    weight: float           # the pixel filter's weight of this sample
    depth: int
    rays: int               # rays traced for this path (camera, continuation, shadow, probes)
    rng: wp.uint32          # the independent sampler's stream


@wp.struct
class MediumState:
    """A path's state in participating media (pbrt-v4's volpath, renderer.integrators.media_path)."""

    medium: int           # the medium the path is in, -1 vacuum
    c: int                # the channel that samples distances
    r_u: wp.vec3          # the channels' path densities over channel c's
    rng: wp.uint32        # tracking's own random numbers


@wp.struct
class ShadowRay:
    """A light sample's shadow ray and what it adds to the path's radiance when nothing blocks it."""

    on: bool                # False: no shadow ray (t_max may be negative for a light closer than the offsets)
    o: wp.vec3
    d: wp.vec3
    t_max: float
    L: wp.vec3


@wp.struct
class PathBuffers:
    """Every path of one launch, a field per array (see the module docstring)."""

    o: wp.array(dtype=wp.vec3)
    d: wp.array(dtype=wp.vec3)
    L: wp.array(dtype=wp.vec3)
    beta: wp.array(dtype=wp.vec3)
    prev_p: wp.array(dtype=wp.vec3)
    eta_scale: wp.array(dtype=float)
    prev_pdf: wp.array(dtype=float)
    prev_specular: wp.array(dtype=wp.bool)
    hero: wp.array(dtype=float)
    weight: wp.array(dtype=float)
    depth: wp.array(dtype=int)
    rays: wp.array(dtype=int)
    rng: wp.array(dtype=wp.uint32)
    sample: wp.array(dtype=PixelSample)     # the pixel sample the scene's sampler draws from (unused: 1 entry)
    hit: wp.array(dtype=Hit)                # the last intersection
    material: wp.array(dtype=int)           # the hit's material, mixes resolved
    ns: wp.array(dtype=wp.vec3)             # the bump step's shading normal (unused without it: 1 entry)
    exit: wp.array(dtype=Exit)              # where the probe step left the vertex (unused without it: 1 entry)
    entry: wp.array(dtype=wp.vec4)          # a coated body's entry weight and q, for the probe step (1 entry without)
    shadow_o: wp.array(dtype=wp.vec3)
    shadow_d: wp.array(dtype=wp.vec3)
    shadow_t: wp.array(dtype=float)
    shadow_L: wp.array(dtype=wp.vec3)
    media: wp.array(dtype=MediumState)      # with media: each path's (unused without: 1 entry)
    shadow_medium: wp.array(dtype=int)      # with media: the medium the shadow ray starts in (1 entry without)
    queue: wp.array2d(dtype=int)            # per queue (RAYS ... REDIRECTED, then one per material kind), path indices
    queued: wp.array(dtype=int)             # per queue, the paths pushed into it
    queue_of_kind: wp.array(dtype=int)      # per material kind id, its shading queue


#: The queues of :class:`PathBuffers`: paths whose next ray is to be traced, paths with a shadow
#: ray to trace, paths whose material has a bump map (the bump step), shadow rays that meet thin
#: slabs' faces (the lens step); with media, paths whose ray reached its surface through the media
#: (on to ``hits``) and paths whose next ray was set without shading (a scattering in a medium, a
#: crossing of an interface: traced again); then one shading queue per material kind of the scene.
RAYS, SHADOWS, BUMPS, LENSES, ARRIVED, REDIRECTED, FIRST_KIND = 0, 1, 2, 3, 4, 5, 6


def path_buffers(n: int, sampled: bool, queue_of_kind: list[int], shading_queues: int, device: str,
                 bumped: bool = False, media: bool = False, probed: bool = False,
                 entered: bool = False) -> PathBuffers:
    """Buffers for ``n`` paths; ``sampled``: the scene's sampler (not the independent stream) draws
    the numbers, so each path keeps its pixel sample; ``queue_of_kind``: per material kind id, its
    first shading queue (from FIRST_KIND on; -1: none) of ``shading_queues``; ``bumped``: the bump
    step runs, so each path keeps its shading normal; ``media``: each path keeps its medium state;
    ``probed``: the probe step runs, so each path keeps where its subsurface step left it;
    ``entered``: a film's entry step runs before it (renderer.integrators.film_entry)."""
    def a(dtype, count: int | tuple[int, int] = n) -> wp.array:
        return wp.zeros(count, dtype=dtype, device=device)

    b = PathBuffers()
    for name in ("o", "d", "L", "beta", "prev_p", "shadow_o", "shadow_d", "shadow_L"):
        setattr(b, name, a(wp.vec3))
    for name in ("eta_scale", "prev_pdf", "hero", "weight", "shadow_t"):
        setattr(b, name, a(float))
    for name in ("depth", "rays", "material"):
        setattr(b, name, a(int))
    b.prev_specular = a(wp.bool)
    b.rng = a(wp.uint32)
    b.sample = a(PixelSample, n if sampled else 1)
    b.hit = a(Hit)
    b.ns = a(wp.vec3, n if bumped else 1)
    b.exit = a(Exit, n if probed else 1)
    b.entry = a(wp.vec4, n if entered else 1)
    b.media = a(MediumState, n if media else 1)
    b.shadow_medium = a(int, n if media else 1)
    b.queue_of_kind = wp.array(queue_of_kind, dtype=int, device=device)
    queues = FIRST_KIND + shading_queues
    b.queued = a(int, queues)
    b.queue = a(int, (queues, n))
    return b


def bytes_per_path(sampled: bool, queues: int, bumped: bool = True, media: bool = True, probed: bool = True) -> int:
    """Device memory of :class:`PathBuffers` per path, from its fields' types: every per-path array,
    the pixel sample only when ``sampled``, the shading normal only when ``bumped``, the medium
    state only with ``media``, the probe step's exit (and a film's entry) only when ``probed``, and one index in each of
    ``queues`` queues (the queue counters and the kind table do not grow with the paths)."""
    unused = {"queued", "queue_of_kind"} | ({"sample"} if not sampled else set()) | (
        {"ns"} if not bumped else set()) | ({"media", "shadow_medium"} if not media else set()) | (
        {"exit", "entry"} if not probed else set())
    total = 0
    for name, var in PathBuffers.vars.items():
        if name in unused:
            continue
        total += wp.types.type_size_in_bytes(var.type.dtype) * (queues if name == "queue" else 1)
    return total


@wp.func
def load_path(b: PathBuffers, i: int) -> PathState:
    st = PathState()
    st.o = b.o[i]
    st.d = b.d[i]
    st.L = b.L[i]
    st.beta = b.beta[i]
    st.prev_p = b.prev_p[i]
    st.eta_scale = b.eta_scale[i]
    st.prev_pdf = b.prev_pdf[i]
    st.prev_specular = b.prev_specular[i]
    st.hero = b.hero[i]
    st.weight = b.weight[i]
    st.depth = b.depth[i]
    st.rays = b.rays[i]
    st.rng = b.rng[i]
    return st


@wp.func
def store_scattered(b: PathBuffers, i: int, st: PathState):
    """What a shaded vertex changes: not the radiance (the shadow kernel adds to it) nor the filter's
    weight, so a shading kernel need not keep them live from its load to its store."""
    b.o[i] = st.o
    b.d[i] = st.d
    b.beta[i] = st.beta
    b.prev_p[i] = st.prev_p
    b.eta_scale[i] = st.eta_scale
    b.prev_pdf[i] = st.prev_pdf
    b.prev_specular[i] = st.prev_specular
    b.hero[i] = st.hero
    b.depth[i] = st.depth
    b.rays[i] = st.rays
    b.rng[i] = st.rng


@wp.func
def store_path(b: PathBuffers, i: int, st: PathState):
    store_scattered(b, i, st)
    b.L[i] = st.L
    b.weight[i] = st.weight


@wp.func
def push(b: PathBuffers, queue: int, i: int):
    """Path ``i`` into ``queue`` (an atomic counter hands out the places; their order does not
    matter, as every path's result is its own)."""
    b.queue[queue, wp.atomic_add(b.queued, queue, 1)] = i


@wp.func
def push_shadow(b: PathBuffers, i: int, sh: ShadowRay):
    b.shadow_t[i] = sh.t_max
    b.shadow_o[i] = sh.o
    b.shadow_d[i] = sh.d
    b.shadow_L[i] = sh.L
    push(b, SHADOWS, i)
