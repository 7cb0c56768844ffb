"""Device side of pbrt-v4's TabulatedBSSRDF: the photon-beam-diffusion table of
:mod:`renderer.materials.beam_diffusion` (in the scene's layer table from ``b.table_first``),
interpolated with Catmull-Rom splines in albedo and optical radius, as pbrt-v4 does.

- ``profile(rows, first, rho, sigma_t, r)`` gives (S_r, pdf_r): the radial profile per unit area
  S_r(r) = sigma_t^2 P(rho, r sigma_t) / (2 pi r sigma_t), P the tabulated 2 pi r S, and the density
  per unit area with which ``sample_radius`` picks r: S_r / rho_eff(rho). Both come from the same
  spline, so the density is the sampler's exact one and integrates to 1 over the plane.
- ``sample_radius(rows, first, rho, u)`` inverts the spline's integral in optical radius: the
  interval from the interpolated CDF, then Newton steps with bisection on the cubic segment.
- ``albedo_from_reflectance`` reads the inverse table rho(rho_eff) (pbrt-v4's SubsurfaceFromDiffuse);
  ``probe_radius`` the radius of the probe sphere.
"""
from __future__ import annotations

import warp as wp

from renderer.materials.beam_diffusion import (N_INVERSE, N_RADIUS, N_RHO, OFF_CDF, OFF_EFF, OFF_INVERSE,
                                               OFF_PROFILE, OFF_RADIUS, OFF_RHO, OFF_RMAX)
from renderer.vecmath import PI

_N_RHO = wp.constant(N_RHO)
_N_RADIUS = wp.constant(N_RADIUS)
_N_INVERSE = wp.constant(N_INVERSE)
_OFF_RHO = wp.constant(OFF_RHO)
_OFF_RADIUS = wp.constant(OFF_RADIUS)
_OFF_EFF = wp.constant(OFF_EFF)
_OFF_PROFILE = wp.constant(OFF_PROFILE)
_OFF_CDF = wp.constant(OFF_CDF)
_OFF_INVERSE = wp.constant(OFF_INVERSE)
_OFF_RMAX = wp.constant(OFF_RMAX)
#: Most Newton/bisection steps when inverting one spline segment.
MAX_NEWTON = 40


@wp.struct
class Spline:
    """Catmull-Rom weights of the four nodes from ``offset`` (offset may be -1: its weight is 0)."""

    offset: int
    w: wp.vec4
    ok: bool


@wp.func
def _lane(v: wp.vec4, j: int) -> float:
    """v[j] for a run-time j by selects: indexed directly, CUDA stores the vector to local memory
    and loads the lane back (four stores and a load per table read, docs/gpu.md)."""
    return wp.where(j < 2, wp.where(j == 0, v[0], v[1]), wp.where(j == 2, v[2], v[3]))


@wp.func
def table_float(rows: wp.array(dtype=wp.vec4), first: int, i: int) -> float:
    """Float i of a material's table (the floats start after its header row)."""
    return _lane(rows[first + 1 + i // 4], i % 4)


@wp.func
def _interval(rows: wp.array(dtype=wp.vec4), first: int, off: int, n: int, x: float) -> int:
    """The k in [0, n - 2] with node k <= x < node k+1 (clamped), by bisection."""
    lo = int(0)
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if table_float(rows, first, off + mid) <= x:
            lo = mid
        else:
            hi = mid
    return lo


@wp.func
def spline_weights(rows: wp.array(dtype=wp.vec4), first: int, off: int, n: int, x: float) -> Spline:
    """Weights of the cubic Hermite spline whose slopes are finite differences of the neighbours
    (one-sided at the ends); ok false outside [node 0, node n-1]."""
    sp = Spline()
    x_first = table_float(rows, first, off)
    x_last = table_float(rows, first, off + n - 1)
    if not (x >= x_first and x <= x_last):
        sp.ok = False
        return sp
    k = _interval(rows, first, off, n, x)
    x0 = table_float(rows, first, off + k)
    x1 = table_float(rows, first, off + k + 1)
    t = (x - x0) / (x1 - x0)
    t2 = t * t
    t3 = t2 * t
    h10 = t3 - 2.0 * t2 + t         # weight of the slope at x0 (per unit t)
    h11 = t3 - t2                   # of the slope at x1
    w = wp.vec4(0.0, 2.0 * t3 - 3.0 * t2 + 1.0, -2.0 * t3 + 3.0 * t2, 0.0)
    if k > 0:
        a = (x1 - x0) / (x1 - table_float(rows, first, off + k - 1))
        w[0] = -h10 * a
        w[2] = w[2] + h10 * a
    else:
        w[1] = w[1] - h10
        w[2] = w[2] + h10
    if k + 2 < n:
        a = (x1 - x0) / (table_float(rows, first, off + k + 2) - x0)
        w[1] = w[1] - h11 * a
        w[3] = h11 * a
    else:
        w[1] = w[1] - h11
        w[2] = w[2] + h11
    sp.offset = k - 1
    sp.w = w
    sp.ok = True
    return sp


@wp.func
def _row_mix(rows: wp.array(dtype=wp.vec4), first: int, off: int, a: Spline, col: int) -> float:
    """Sum over the four albedo rows of a table (profile or CDF) at one radius column."""
    v = float(0.0)
    for j in range(4):
        w = _lane(a.w, j)
        if w != 0.0:
            v += w * table_float(rows, first, off + (a.offset + j) * _N_RADIUS + col)
    return v


@wp.func
def _effective_albedo(rows: wp.array(dtype=wp.vec4), first: int, a: Spline) -> float:
    v = float(0.0)
    for j in range(4):
        w = _lane(a.w, j)
        if w != 0.0:
            v += w * table_float(rows, first, _OFF_EFF + a.offset + j)
    return v


@wp.func
def effective_albedo(rows: wp.array(dtype=wp.vec4), first: int, rho: float) -> float:
    """rho_eff(rho): the share of the light that enters that leaves again (the profile's integral)."""
    a = spline_weights(rows, first, _OFF_RHO, _N_RHO, rho)
    return wp.where(a.ok, _effective_albedo(rows, first, a), 0.0)


@wp.func
def profile(rows: wp.array(dtype=wp.vec4), first: int, rho: float, sigma_t: float, r: float) -> wp.vec2:
    """(S_r(r), pdf of sample_radius at r), both per unit area, for one channel."""
    if sigma_t <= 0.0:
        return wp.vec2(0.0)
    r_opt = r * sigma_t
    a = spline_weights(rows, first, _OFF_RHO, _N_RHO, rho)
    b = spline_weights(rows, first, _OFF_RADIUS, _N_RADIUS, r_opt)
    if not (a.ok and b.ok):
        return wp.vec2(0.0)
    p = float(0.0)
    for k in range(4):
        w = _lane(b.w, k)
        if w != 0.0:
            p += w * _row_mix(rows, first, _OFF_PROFILE, a, b.offset + k)
    if r_opt > 0.0:
        p = p / (2.0 * PI * r_opt)
    sr = wp.max(p * sigma_t * sigma_t, 0.0)
    eff = _effective_albedo(rows, first, a)
    return wp.vec2(sr, wp.where(eff > 0.0, sr / eff, 0.0))


@wp.func
def sample_radius(rows: wp.array(dtype=wp.vec4), first: int, rho: float, u: float) -> float:
    """An optical radius with density P(rho, r) / rho_eff(rho) per unit radius; -1 on failure."""
    a = spline_weights(rows, first, _OFF_RHO, _N_RHO, rho)
    if not a.ok:
        return -1.0
    total = _row_mix(rows, first, _OFF_CDF, a, _N_RADIUS - 1)
    if total <= 0.0:
        return -1.0
    target = u * total
    # the interval whose interpolated CDF brackets the target
    lo = int(0)
    hi = _N_RADIUS - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if _row_mix(rows, first, _OFF_CDF, a, mid) <= target:
            lo = mid
        else:
            hi = mid
    k = lo
    f0 = _row_mix(rows, first, _OFF_PROFILE, a, k)
    f1 = _row_mix(rows, first, _OFF_PROFILE, a, k + 1)
    x0 = table_float(rows, first, _OFF_RADIUS + k)
    x1 = table_float(rows, first, _OFF_RADIUS + k + 1)
    width = x1 - x0
    d0 = f1 - f0
    d1 = f1 - f0
    if k > 0:
        d0 = width * (f1 - _row_mix(rows, first, _OFF_PROFILE, a, k - 1)) / (x1 - table_float(rows, first, _OFF_RADIUS + k - 1))
    if k + 2 < _N_RADIUS:
        d1 = width * (_row_mix(rows, first, _OFF_PROFILE, a, k + 2) - f0) / (table_float(rows, first, _OFF_RADIUS + k + 2) - x0)
    v = (target - _row_mix(rows, first, _OFF_CDF, a, k)) / width
    # cubic segment f(t) = f0 + c1 t + c2 t^2 + c3 t^3 and its integral; start from the linear segment's inverse
    c1 = d0
    c2 = 3.0 * (f1 - f0) - 2.0 * d0 - d1
    c3 = 2.0 * (f0 - f1) + d0 + d1
    t = float(0.0)
    if f0 != f1:
        t = (f0 - wp.sqrt(wp.max(f0 * f0 + 2.0 * v * (f1 - f0), 0.0))) / (f0 - f1)
    elif f0 > 0.0:
        t = v / f0
    lo_t = float(0.0)
    hi_t = float(1.0)
    for it in range(MAX_NEWTON):
        if not (t >= lo_t and t <= hi_t):
            t = 0.5 * (lo_t + hi_t)
        F = t * (f0 + t * (0.5 * c1 + t * (c2 / 3.0 + t * 0.25 * c3)))
        f = f0 + t * (c1 + t * (c2 + t * c3))
        err = F - v
        if wp.abs(err) < 1.0e-6 or hi_t - lo_t < 1.0e-6:
            break
        if err < 0.0:
            lo_t = t
        else:
            hi_t = t
        if f != 0.0:
            t = t - err / f
        else:
            t = 0.5 * (lo_t + hi_t)
    return x0 + width * t


@wp.func
def albedo_from_reflectance(rows: wp.array(dtype=wp.vec4), first: int, reflectance: float) -> float:
    """The single-scattering albedo whose effective albedo is ``reflectance`` (clamped to [0, 1];
    above the table's rho_eff(1) it is 1, as pbrt-v4's inversion clamps)."""
    eff_max = rows[first][1]
    x = wp.clamp(reflectance, 0.0, 1.0) / eff_max * float(_N_INVERSE - 1)
    if x >= float(_N_INVERSE - 1):
        return table_float(rows, first, _OFF_INVERSE + _N_INVERSE - 1)
    i = int(x)
    f = x - float(i)
    return (1.0 - f) * table_float(rows, first, _OFF_INVERSE + i) + f * table_float(rows, first, _OFF_INVERSE + i + 1)


@wp.func
def probe_radius(rows: wp.array(dtype=wp.vec4), first: int, rho: float) -> float:
    """The optical radius of the probe sphere at albedo rho: the table's 99.9 % radius per albedo
    node, linear in rho (any bound serves, as long as sampling and density use the same one)."""
    k = _interval(rows, first, _OFF_RHO, _N_RHO, rho)
    x0 = table_float(rows, first, _OFF_RHO + k)
    x1 = table_float(rows, first, _OFF_RHO + k + 1)
    f = wp.clamp((rho - x0) / (x1 - x0), 0.0, 1.0)
    return (1.0 - f) * table_float(rows, first, _OFF_RMAX + k) + f * table_float(rows, first, _OFF_RMAX + k + 1)
