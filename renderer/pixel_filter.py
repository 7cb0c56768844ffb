"""pbrt-v4's pixel filters sampled by importance, as its ``FilterSampler`` does: the filter is
tabulated at 32 cells per unit of radius, a camera sample's offset from the pixel centre is drawn
from the table's |f| and carries the weight f/pdf, which is ± the same constant everywhere. There
is no splatting: each sample still belongs to one pixel, so passes stay independent.

pbrt-v4's filters are all separable, f(x, y) = f(x) f(y), so the 2D table's distribution is the
product of two 1D ones and each axis is sampled on its own. The weight here is divided by the
filter's (tabulated) integral, so its mean is 1 and the film stays a plain mean of its samples
(pbrt divides by the sum of the weights instead; both converge to the same filtered image).
The box filter (this renderer's default, radius 0.5) and the triangle are sampled exactly, as pbrt
does; the box of radius 0.5 returns the two random numbers unchanged, keeping old images exact."""
from __future__ import annotations

import math

import numpy as np
import warp as wp

from renderer.scene.description import FilterDesc

BOX, TENT, TABLE = 0, 1, 2
#: pbrt-v4's FilterSampler resolution: table cells per unit of filter radius.
CELLS_PER_RADIUS = 32


@wp.struct
class PixelFilter:
    kind: int
    radius: wp.vec2
    n: wp.vec2i                        # table cells along x and y (TABLE only)
    cdf: wp.array(dtype=float)         # x's n[0] + 1 entries, then y's n[1] + 1
    sign: wp.array(dtype=float)        # the sign of f per cell, indexed as cdf
    norm: float                        # integral of |f| over integral of f (the weight's magnitude)


@wp.struct
class FilterSample:
    p: wp.vec2                         # where in the pixel, from its corner: the centre is (0.5, 0.5)
    weight: float


@wp.func
def _tent(u: float, r: float) -> float:
    """pbrt's SampleTent: the density (r - |x|) / r^2 on [-r, r]."""
    if u < 0.5:
        return -r + r * wp.sqrt(2.0 * u)
    return r - r * wp.sqrt(2.0 - 2.0 * u)


@wp.func
def _cell(f: PixelFilter, start: int, n: int, u: float, r: float) -> wp.vec2:
    """Invert a piecewise-constant CDF: (the offset in [-r, r], the cell's sign)."""
    lo = int(0)
    hi = n
    while hi - lo > 1:                 # the last cell i with cdf[i] <= u
        mid = (lo + hi) // 2
        if f.cdf[start + mid] <= u:
            lo = mid
        else:
            hi = mid
    c0 = f.cdf[start + lo]
    width = f.cdf[start + lo + 1] - c0
    t = float(0.5)
    if width > 0.0:
        t = wp.clamp((u - c0) / width, 0.0, 1.0)
    x = -r + 2.0 * r * (float(lo) + t) / float(n)
    return wp.vec2(x, f.sign[start + lo])


@wp.func
def sample_filter(f: PixelFilter, u: wp.vec2) -> FilterSample:
    """The point in the pixel a camera ray goes through and its weight, from two random numbers."""
    s = FilterSample()
    s.weight = 1.0
    if f.kind == BOX:
        s.p = wp.vec2((0.5 - f.radius[0]) + (2.0 * f.radius[0]) * u[0],
                      (0.5 - f.radius[1]) + (2.0 * f.radius[1]) * u[1])
    elif f.kind == TENT:
        s.p = wp.vec2(0.5 + _tent(u[0], f.radius[0]), 0.5 + _tent(u[1], f.radius[1]))
    else:
        x = _cell(f, 0, f.n[0], u[0], f.radius[0])
        y = _cell(f, f.n[0] + 1, f.n[1], u[1], f.radius[1])
        s.p = wp.vec2(0.5 + x[0], 0.5 + y[0])
        s.weight = x[1] * y[1] * f.norm
    return s


def filter_1d(desc: FilterDesc, x: np.ndarray, axis: int) -> np.ndarray:
    """pbrt-v4's filter along one axis (its filters.h), at offsets ``x``."""
    r = desc.radius[axis]
    ax = np.abs(x)
    if desc.kind == "box":
        return (ax <= r).astype(np.float64)
    if desc.kind == "triangle":
        return np.maximum(0.0, r - ax)
    if desc.kind == "gaussian":
        g = lambda v: np.exp(-v * v / (2.0 * desc.sigma ** 2)) / math.sqrt(2.0 * math.pi * desc.sigma ** 2)
        return np.maximum(0.0, g(x) - g(r))
    if desc.kind == "mitchell":
        t, b, c = np.abs(2.0 * x / r), desc.b, desc.c
        inner = ((12 - 9 * b - 6 * c) * t ** 3 + (-18 + 12 * b + 6 * c) * t ** 2 + (6 - 2 * b)) / 6.0
        outer = ((-b - 6 * c) * t ** 3 + (6 * b + 30 * c) * t ** 2 + (-12 * b - 48 * c) * t + (8 * b + 24 * c)) / 6.0
        return np.where(t <= 1.0, inner, np.where(t <= 2.0, outer, 0.0))
    if desc.kind == "sinc":          # Lanczos: sinc(x) sinc(x / tau) inside the radius
        return np.where(ax <= r, np.sinc(x) * np.sinc(x / desc.tau), 0.0)
    raise ValueError(f"unknown pixel filter {desc.kind!r}")


def filter_table(desc: FilterDesc, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """pbrt's tabulation along one axis: f at the centres of int(32 r) cells over [-r, r]."""
    r = desc.radius[axis]
    n = max(1, int(CELLS_PER_RADIUS * r))
    centres = -r + 2.0 * r * (np.arange(n) + 0.5) / n
    return centres, filter_1d(desc, centres, axis)


def build_pixel_filter(desc: FilterDesc, device: str) -> tuple[PixelFilter, list]:
    """The device filter and the arrays it points into (keep them alive)."""
    f = PixelFilter()
    f.radius = wp.vec2(*desc.radius)
    f.kind = {"box": BOX, "triangle": TENT}.get(desc.kind, TABLE)
    cdfs, signs, norm, n = [], [], 1.0, [1, 1]
    if f.kind == TABLE:
        for axis in (0, 1):
            _, values = filter_table(desc, axis)
            a = np.abs(values)
            if not a.sum() > 0.0 or not values.sum() > 0.0:
                raise ValueError(f"pixel filter {desc.kind}: its integral along an axis is not positive")
            cdfs.append(np.concatenate([[0.0], np.cumsum(a) / a.sum()]))
            signs.append(np.append(np.sign(values), 0.0))     # laid out as the CDF
            norm *= a.sum() / values.sum()
            n[axis] = len(values)
    f.n = wp.vec2i(*n)
    f.norm = float(norm)
    f.cdf = wp.array(np.concatenate(cdfs) if cdfs else np.zeros(1), dtype=float, device=device)
    f.sign = wp.array(np.concatenate(signs) if signs else np.zeros(1), dtype=float, device=device)
    return f, [f.cdf, f.sign]
