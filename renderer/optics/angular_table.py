"""Tables over the angle of incidence: a material's RGB reflectance (and transmittance) baked at
upload from the exact per-wavelength optics, integrated at every nanometre of 360–830 against the
CIE 1931 observer under D65, then looked up on the device by linear interpolation.

Why: the RGB colour of a coating or a measured conductor depends on the material and on one
number at the hit, the cosine of incidence. A 200-layer stack costs about a millisecond per
spectral evaluation; its table costs one lookup, and it is the 1 nm reference itself (no
wavelength noise), so R + T = 1 per channel for lossless media, sample by sample.

Grid. R(cos θ) is smooth except at a critical angle of the substrate (n_sub < n_0): there the
substrate's normal wavenumber q = n_0 sqrt(cos² θ − a), a = 1 − n_sub²/n_0², has a square-root
branch point, R has an infinite slope, and linear interpolation in cos θ would miss by ~sqrt(h).
Interior layers add no branch point (a finite layer's characteristic matrix is even in its own
q). So the table is uniform in y = sign(cos² θ − a)·sqrt(|cos² θ − a|), in which R is smooth on
either side of y = 0, and y = 0 is a node (R's kink there is then exact). Without a critical
angle (a = 0) y is cos θ itself.

Rows are ``wp.vec4`` in the scene's layer table (:mod:`renderer.materials.stack`): a header
(node count, index of the node at y = 0, a, 0), then ``stride`` rows per node. Both ends are
nodes (cos θ = 0 and 1), so the spacing in y differs below and above y = 0.
"""
from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache

import numpy as np
import warp as wp

from renderer.color import spectral
from renderer.optics.fresnel import fresnel_conductor
from renderer.optics.multilayer import multilayer_RT

wp.set_module_options({"fast_math": False, "enable_backward": False})

#: Nodes over cos θ by default, chosen by measurement (benchmarks/thin_film_modes.py --stacks): at
#: 512 nodes the largest R error against the 1 nm reference at random angles is ~1e-4 for stacks
#: of up to 40 layers; beyond ~100 layers the table's error falls below the 1 nm reference's own
#: (its difference from a 0.25 nm integration: fringes finer than a nanometre).
DEFAULT_NODES = 512


def grid(a: float, n_nodes: int) -> tuple[np.ndarray, int]:
    """(cos θ at each node, index of the node at y = 0) for branch point a: uniform in y on
    [−sqrt(a), 0] and on [0, sqrt(1 − a)], with nodes at both ends (cos θ = 0 and 1) and at 0."""
    a = min(max(float(a), 0.0), 1.0 - 1e-6)
    lo, hi = math.sqrt(a), math.sqrt(1.0 - a)
    below = 0 if a == 0.0 else min(max(round((n_nodes - 1) * lo / (lo + hi)), 1), n_nodes - 2)
    above = max(n_nodes - 1 - below, 1)
    y = np.r_[np.linspace(-lo, 0.0, below + 1)[:-1], np.linspace(0.0, hi, above + 1)]
    return np.sqrt(np.clip(a + y * np.abs(y), 0.0, 1.0)), below


def header(n_nodes: int, zero: int, a: float) -> np.ndarray:
    return np.array([[n_nodes, zero, a, 0.0]], np.float32)


def branch_point(n0: float, n_sub: complex) -> float:
    """a = 1 − n_sub²/n_0² where the (real part of the) substrate index is below the incident one."""
    return max(0.0, 1.0 - (np.real(n_sub) / n0) ** 2)


@wp.func
def table_locate(rows: wp.array(dtype=wp.vec4), first: int, cos_w: float) -> wp.vec2:
    """(node j, weight t of node j + 1) of |cos_w| in the table whose header is rows[first]."""
    head = rows[first]
    n = int(head[0])
    zero = head[1]
    a = head[2]
    c = wp.min(wp.abs(cos_w), 1.0)
    d = c * c - a
    x = zero + wp.sqrt(wp.abs(d)) * (float(n - 1) - zero) / wp.sqrt(1.0 - a)      # the uniform part above y = 0
    if d < 0.0:
        x = zero * (1.0 - wp.sqrt(-d / a))                                       # and below it (a > 0 here)
    x = wp.clamp(x, 0.0, float(n - 1))
    j = wp.min(int(wp.floor(x)), n - 2)
    return wp.vec2(float(j), x - float(j))


@wp.func
def table_value(rows: wp.array(dtype=wp.vec4), first: int, stride: int, offset: int, at: wp.vec2) -> wp.vec3:
    """The interpolated row ``offset`` of the nodes around ``at`` (from :func:`table_locate`), as RGB."""
    j = int(at[0])
    lo = rows[first + 1 + j * stride + offset]
    hi = rows[first + 1 + (j + 1) * stride + offset]
    v = lo + at[1] * (hi - lo)
    return wp.vec3(v[0], v[1], v[2])


@wp.kernel
def _stack_bake_kernel(offset: int, cos0: wp.array(dtype=float), n0: float, n_sub: wp.vec2, layers: wp.array(dtype=wp.vec4),
                       count: int, lam: wp.array(dtype=float), weights: wp.array(dtype=wp.vec3),
                       out: wp.array(dtype=wp.vec4)):
    i = wp.tid() + offset
    r = wp.vec3(0.0)
    t = wp.vec3(0.0)
    for j in range(lam.shape[0]):
        rt = multilayer_RT(cos0[i], lam[j], n0, n_sub, layers, 0, count, False, 1.0)
        r += rt[0] * weights[j]
        t += rt[1] * weights[j]
    out[2 * i] = wp.vec4(r[0], r[1], r[2], 0.0)
    out[2 * i + 1] = wp.vec4(t[0], t[1], t[2], 0.0)


@wp.kernel
def _conductor_bake_kernel(offset: int, cos0: wp.array(dtype=float), eta: wp.array(dtype=float), k: wp.array(dtype=float),
                           weights: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec4)):
    i = wp.tid() + offset
    r = wp.vec3(0.0)
    for j in range(eta.shape[0]):
        r += fresnel_conductor(cos0[i], wp.vec3(eta[j]), wp.vec3(k[j]))[0] * weights[j]
    out[i] = wp.vec4(r[0], r[1], r[2], 0.0)


def _bake(kernel: wp.Kernel, n: int, inputs: list) -> None:
    """Launches a bake kernel over n nodes on the CPU, in slices on as many threads as there are
    cores (a CPU launch runs on one thread and releases the GIL); each node writes only its own rows."""
    threads = max(1, min(os.cpu_count() or 1, 16, n))
    bounds = np.linspace(0, n, threads + 1).astype(int)
    with ThreadPoolExecutor(threads) as pool:
        done = [pool.submit(wp.launch, kernel, dim=int(hi - lo), inputs=[int(lo), *inputs], device="cpu")
                for lo, hi in zip(bounds[:-1], bounds[1:]) if hi > lo]
        for f in done:
            f.result()


def _reference() -> tuple[np.ndarray, wp.array]:
    """The 1 nm wavelengths and their RGB weights (R ≡ 1 sums to white exactly)."""
    lam, weights, _ = spectral.mode_wavelengths("reference")
    return lam, wp.array(weights.astype(np.float32), dtype=wp.vec3, device="cpu")


def _floats(x: np.ndarray) -> wp.array:
    return wp.array(np.ascontiguousarray(x, np.float32), dtype=float, device="cpu")


def stack_table(n0: float, n_sub: complex, layers: np.ndarray, n_nodes: int = DEFAULT_NODES) -> np.ndarray:
    """Rows of the RGB (R, T) table of outer n0 (real) | layers (rows as in multilayer_RT, listed
    from n0's side; none: a bare interface) | substrate n_sub: a header, then R and T per node.
    Materials that share a coating share its bake (cached)."""
    rows = np.ascontiguousarray(layers, np.float32).reshape(-1, 4)
    return _stack_table(float(n0), complex(n_sub), rows.tobytes(), int(n_nodes)).copy()


@lru_cache(maxsize=64)
def _stack_table(n0: float, n_sub: complex, layer_bytes: bytes, n_nodes: int) -> np.ndarray:
    a = branch_point(n0, n_sub) if np.imag(n_sub) == 0.0 else 0.0
    cos, zero = grid(a, n_nodes)
    rows = np.frombuffer(layer_bytes, np.float32).reshape(-1, 4)
    if len(rows) == 0:
        rows = np.array([[n0, 0.0, 0.0, 0.0]], np.float32)
    lam, weights = _reference()
    out = wp.empty(2 * len(cos), dtype=wp.vec4, device="cpu")
    _bake(_stack_bake_kernel, len(cos),
          [_floats(cos), float(n0), wp.vec2(float(np.real(n_sub)), float(np.imag(n_sub))),
           wp.array(rows, dtype=wp.vec4, device="cpu"), len(rows), _floats(lam), weights, out])
    return np.concatenate([header(len(cos), zero, a), out.numpy()])


def conductor_table(eta: np.ndarray, k: np.ndarray, n_nodes: int = DEFAULT_NODES) -> np.ndarray:
    """Rows of the RGB Fresnel reflectance table of a conductor whose eta and k (relative to the
    outside) are given at every nm of 360–830 (:func:`spectral.mode_wavelengths` "reference").
    A colour outside the sRGB gamut keeps a channel above 1 (gold's red is 1.02 at normal
    incidence, as pbrt-v4's sRGB image shows it); a negative channel is clipped to 0, since a
    path's throughput must not carry one."""
    cos, zero = grid(0.0, n_nodes)
    _, weights = _reference()
    out = wp.empty(len(cos), dtype=wp.vec4, device="cpu")
    _bake(_conductor_bake_kernel, len(cos), [_floats(cos), _floats(eta), _floats(k), weights, out])
    return np.concatenate([header(len(cos), zero, 0.0), np.maximum(out.numpy(), 0.0)])


@wp.kernel
def _lookup_kernel(rows: wp.array(dtype=wp.vec4), cos0: wp.array(dtype=float), stride: int, offset: int,
                   out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    out[i] = table_value(rows, 0, stride, offset, table_locate(rows, 0, cos0[i]))


def lookup(rows: np.ndarray, cos_theta, stride: int = 2, offset: int = 0) -> np.ndarray:
    """The device lookup on numpy arrays: row ``offset`` (0: R, 1: T of a stack table) at each cos θ."""
    c = np.asarray(cos_theta, np.float64)
    out = wp.empty(c.size, dtype=wp.vec3, device="cpu")
    wp.launch(_lookup_kernel, dim=c.size, device="cpu",
              inputs=[wp.array(np.asarray(rows, np.float32), dtype=wp.vec4, device="cpu"), _floats(c.ravel()),
                      int(stride), int(offset), out])
    return out.numpy().reshape(c.shape + (3,))
