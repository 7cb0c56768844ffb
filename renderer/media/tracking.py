"""Free-flight sampling in media with null scattering (pbrt-v4's volpath, Novák et al.'s
formulation): along a ray the medium is bounded by a majorant sigma_maj >= sigma_t, piecewise
constant over the cells of a coarse grid (one cell for homogeneous media and clouds), walked
with a DDA. Tentative collisions are sampled against sigma_maj and split into absorption,
real scattering and null collisions.

Colour: every coefficient is RGB. A path picks one channel c (uniformly, once) and samples
distances with that channel's majorant; the throughput ``beta`` carries f/p_c per channel and
``r_u`` the ratios p_i/p_c of the other channels' sampling densities. A contribution divided
by the mean of r_u is the one-sample balance heuristic over the three channels (pbrt-v4's
spectral MIS over its wavelengths), so chromatic media stay unbiased in every channel.

- :func:`delta_track`: the path's next event before t_max: a real scattering (with the
  point's phase asymmetry), absorption (the path ends) or none; emission of the medium at each
  tentative collision is added on the way.
- :func:`ratio_track`: the transmittance of a shadow-ray segment, per channel (ratio tracking
  with the same majorants, with pbrt-v4's Russian roulette once it falls under 0.05)."""
from __future__ import annotations

import warp as wp

from renderer.media.device import (CLOUD, HOMOGENEOUS, LOG_T_MIN, LOG_T_STEP, NANOVDB, RGBGRID, TABLE_LAST,
                                   UNIFORMGRID, Media)
from renderer.textures.noise import noise
from renderer.vecmath import added, component, mean3

#: what delta tracking ends with
PASSED, SCATTERED, ABSORBED = wp.constant(0), wp.constant(1), wp.constant(2)
INF = wp.constant(1.0e30)


@wp.struct
class MediumPoint:
    sigma_a: wp.vec3
    sigma_s: wp.vec3
    Le: wp.vec3


@wp.func
def _grid_index(media: Media, mi: int, pm: wp.vec3) -> wp.vec3:
    """pbrt's SampledGrid look-up point p * n - 0.5, p in [0, 1]^3 over the bounds: the volume's index space."""
    u = wp.cw_div(pm - media.lo[mi], media.hi[mi] - media.lo[mi])
    return wp.cw_mul(u, media.res[mi]) - wp.vec3(0.5)


@wp.func
def cloud_density(media: Media, mi: int, p: wp.vec3) -> float:
    """pbrt-v4's CloudMedium density at p (medium space): noise octaves at a wispy-perturbed point,
    thinning with height y."""
    cl = media.cloud[mi]
    pp = p * cl[2]
    if cl[1] > 0.0:
        vomega = 0.05 * cl[1]
        vlambda = float(10.0)
        for _i in range(2):
            q = pp * vlambda
            n = noise(media.perm, q)
            dn = wp.vec3(noise(media.perm, q + wp.vec3(0.01, 0.0, 0.0)) - n,
                         noise(media.perm, q + wp.vec3(0.0, 0.01, 0.0)) - n,
                         noise(media.perm, q + wp.vec3(0.0, 0.0, 0.01)) - n) / 0.01
            pp = pp + dn * vomega
            vomega *= 0.5
            vlambda *= 1.99
    d = float(0.0)
    omega = float(0.5)
    lam = float(1.0)
    for _i in range(5):
        d += omega * noise(media.perm, pp * lam)
        omega *= 0.5
        lam *= 1.99
    d = wp.clamp((1.0 - p[1]) * 4.5 * cl[0] * d, 0.0, 1.0)
    d += 2.0 * wp.max(0.0, 0.5 - p[1])
    return wp.clamp(d, 0.0, 1.0)


@wp.func
def _temperature_emission(media: Media, mi: int, x: wp.vec3) -> wp.vec3:
    """pbrt's peak-normalised blackbody at the grid's temperature, offset and scaled; 0 up to 100 K."""
    tp = media.temperature[mi]
    t = (wp.volume_sample_f(media.vol[mi, 3], x, wp.Volume.LINEAR) - tp[0]) * tp[1]
    if t <= 100.0:
        return wp.vec3(0.0)
    f = wp.clamp((wp.log(t) - LOG_T_MIN) / LOG_T_STEP, 0.0, float(TABLE_LAST))
    i = wp.min(int(f), TABLE_LAST - 1)
    a = f - float(i)
    return media.blackbody[i] * (1.0 - a) + media.blackbody[i + 1] * a


@wp.func
def properties(media: Media, mi: int, p: wp.vec3) -> MediumPoint:
    """sigma_a, sigma_s and Le of medium ``mi`` at world point p."""
    r = MediumPoint()
    r.sigma_a = media.sigma_a[mi]
    r.sigma_s = media.sigma_s[mi]
    r.Le = media.Le[mi]
    k = media.kind[mi]
    if k == HOMOGENEOUS:
        return r
    pm = wp.transform_point(media.to_medium[mi], p)
    if k == UNIFORMGRID:
        x = _grid_index(media, mi, pm)
        dens = wp.volume_sample_f(media.vol[mi, 0], x, wp.Volume.LINEAR)
        r.sigma_a = r.sigma_a * dens
        r.sigma_s = r.sigma_s * dens
        if media.vol[mi, 3] != wp.uint64(0):
            r.Le = _temperature_emission(media, mi, x)
        if wp.max(r.Le) > 0.0:
            # the Lescale grid (slot 1), or pbrt's default (slot 2): a 1x1x1 grid of 1, itself
            # interpolated against zeros outside, so a tent over the bounds
            if media.vol[mi, 1] != wp.uint64(0):
                r.Le = r.Le * wp.volume_sample_f(media.vol[mi, 1], x, wp.Volume.LINEAR)
            else:
                u = wp.cw_div(pm - media.lo[mi], media.hi[mi] - media.lo[mi]) - wp.vec3(0.5)
                r.Le = r.Le * wp.volume_sample_f(media.vol[mi, 2], u, wp.Volume.LINEAR)
    elif k == RGBGRID:
        x = _grid_index(media, mi, pm)
        if media.vol[mi, 0] != wp.uint64(0):
            r.sigma_a = wp.volume_sample_v(media.vol[mi, 0], x, wp.Volume.LINEAR)
        if media.vol[mi, 1] != wp.uint64(0):
            r.sigma_s = wp.volume_sample_v(media.vol[mi, 1], x, wp.Volume.LINEAR)
        if media.vol[mi, 2] != wp.uint64(0):
            r.Le = wp.volume_sample_v(media.vol[mi, 2], x, wp.Volume.LINEAR)
    elif k == CLOUD:
        dens = float(0.0)
        lo = media.lo[mi]
        hi = media.hi[mi]
        if pm[0] >= lo[0] and pm[1] >= lo[1] and pm[2] >= lo[2] and pm[0] <= hi[0] and pm[1] <= hi[1] \
                and pm[2] <= hi[2]:
            dens = cloud_density(media, mi, pm)
        r.sigma_a = r.sigma_a * dens
        r.sigma_s = r.sigma_s * dens
    else:   # NANOVDB
        vid = media.vol[mi, 0]
        dens = wp.volume_sample_f(vid, wp.volume_world_to_index(vid, pm), wp.Volume.LINEAR)
        r.sigma_a = r.sigma_a * dens
        r.sigma_s = r.sigma_s * dens
    return r


@wp.struct
class Majorants:
    """A walk through a medium's majorant cells along a ray: after :func:`next_cell`, [t0, t1] is
    the current cell's stretch of the ray and ``sigma`` its bound; ``valid`` is False past the end."""
    t0: float
    t1: float
    sigma: wp.vec3
    valid: bool
    t: float              # where the walk stands
    t_end: float
    cell: wp.vec3i
    res: wp.vec3i
    first: int
    next_t: wp.vec3       # where the ray crosses the next cell boundary, per axis
    delta_t: wp.vec3
    step: wp.vec3i


@wp.func
def start_cells(media: Media, mi: int, o: wp.vec3, d: wp.vec3, t_max: float) -> Majorants:
    """The walk of the ray o + t d, t in (0, t_max), through medium ``mi``'s majorant grid, clipped to
    its bounds (a homogeneous medium has none: one cell over the whole ray)."""
    w = Majorants()
    w.first = media.maj_first[mi]
    w.res = media.maj_res[mi]
    w.cell = wp.vec3i(0, 0, 0)
    w.step = wp.vec3i(0, 0, 0)
    w.next_t = wp.vec3(INF)
    w.delta_t = wp.vec3(0.0)
    w.t = 0.0
    w.t_end = t_max
    w.valid = True
    k = media.kind[mi]
    if k == HOMOGENEOUS:
        return w
    pm = wp.transform_point(media.to_medium[mi], o)
    dm = wp.transform_vector(media.to_medium[mi], d)
    if k == NANOVDB:
        vid = media.vol[mi, 0]
        pm = wp.volume_world_to_index(vid, pm)
        dm = wp.volume_world_to_index_dir(vid, dm)
    ext = media.hi[mi] - media.lo[mi]
    u = wp.cw_div(pm - media.lo[mi], ext)       # the bounds as [0, 1]^3
    du = wp.cw_div(dm, ext)
    t0 = float(0.0)
    t1 = t_max
    for a in range(3):
        if du[a] == 0.0:
            if u[a] < 0.0 or u[a] > 1.0:
                t1 = -1.0
        else:
            ta = (0.0 - u[a]) / du[a]
            tb = (1.0 - u[a]) / du[a]
            t0 = wp.max(t0, wp.min(ta, tb))
            t1 = wp.min(t1, wp.max(ta, tb))
    if t0 >= t1:
        w.valid = False
        w.t_end = 0.0
        return w
    w.t = t0
    w.t_end = t1
    pu = u + du * t0
    cell = wp.vec3i(0, 0, 0)
    step = wp.vec3i(0, 0, 0)
    next_t = wp.vec3(INF)
    delta_t = wp.vec3(0.0)
    for a in range(3):
        n = w.res[a]
        c = wp.clamp(int(pu[a] * float(n)), 0, n - 1)
        cell[a] = c
        if du[a] > 0.0:
            next_t[a] = t0 + (float(c + 1) / float(n) - pu[a]) / du[a]
            delta_t[a] = 1.0 / (float(n) * du[a])
            step[a] = 1
        elif du[a] < 0.0:
            next_t[a] = t0 + (float(c) / float(n) - pu[a]) / du[a]
            delta_t[a] = -1.0 / (float(n) * du[a])
            step[a] = -1
    w.cell = cell
    w.step = step
    w.next_t = next_t
    w.delta_t = delta_t
    return w


@wp.func
def next_cell(media: Media, w: Majorants) -> Majorants:
    """The walk with [t0, t1] and sigma set to the current cell, standing at the next one."""
    r = w
    if r.t >= r.t_end or not r.valid:
        r.valid = False
        return r
    c = r.cell
    r.sigma = media.maj[r.first + (c[2] * r.res[1] + c[1]) * r.res[0] + c[0]]
    a = int(0)          # the axis crossed next, read and written through component/added
    if r.next_t[1] < r.next_t[0]:
        a = 1
    if r.next_t[2] < component(r.next_t, a):
        a = 2
    r.t0 = r.t
    r.t1 = wp.min(component(r.next_t, a), r.t_end)
    r.t = r.t1
    if r.t < r.t_end:
        c = added(c, a, component(r.step, a))
        r.next_t = added(r.next_t, a, component(r.delta_t, a))
        r.cell = c
        ca = component(c, a)
        if ca < 0 or ca >= component(r.res, a):
            r.t_end = r.t
    return r


@wp.func
def transmittance(sigma: wp.vec3, dt: float) -> wp.vec3:
    """exp(-sigma dt), per channel."""
    return wp.vec3(wp.exp(-sigma[0] * dt), wp.exp(-sigma[1] * dt), wp.exp(-sigma[2] * dt))


@wp.struct
class Flight:
    """Tentative collisions along a ray, one per :func:`next_collision`: free flights against the
    majorant of channel c, cell by cell. At a collision, ``t`` is its distance, ``sigma`` its
    majorant and ``T_maj`` the majorant transmittance since the previous one (the caller resets it)."""
    cells: Majorants
    t: float
    in_cell: bool
    T_maj: wp.vec3
    sigma: wp.vec3
    hit: bool             # False: the ray reached its end, T_maj holding the rest of the way
    c: int
    rng: wp.uint32


@wp.func
def start_flight(media: Media, mi: int, o: wp.vec3, d: wp.vec3, t_max: float, c: int, rng: wp.uint32) -> Flight:
    f = Flight()
    f.cells = start_cells(media, mi, o, d, t_max)
    f.t = 0.0
    f.in_cell = False
    f.T_maj = wp.vec3(1.0)
    f.hit = False
    f.c = c
    f.rng = rng
    return f


@wp.func
def next_collision(media: Media, f: Flight) -> Flight:
    r = f
    state = r.rng
    while True:
        if not r.in_cell:
            r.cells = next_cell(media, r.cells)
            if not r.cells.valid:
                r.hit = False
                r.rng = state
                return r
            r.t = r.cells.t0
            r.in_cell = True
        sigma = r.cells.sigma
        sm = component(sigma, r.c)
        t_next = float(INF)
        if sm > 0.0:
            t_next = r.t - wp.log(1.0 - wp.randf(state)) / sm
        if t_next >= r.cells.t1:
            r.T_maj = wp.cw_mul(r.T_maj, transmittance(sigma, r.cells.t1 - r.t))
            r.in_cell = False
            continue
        r.T_maj = wp.cw_mul(r.T_maj, transmittance(sigma, t_next - r.t))
        r.t = t_next
        r.sigma = sigma
        r.hit = True
        r.rng = state
        return r
    return r


@wp.struct
class Tracked:
    event: int            # PASSED, SCATTERED or ABSORBED
    p: wp.vec3            # the scattering point
    beta: wp.vec3
    r_u: wp.vec3
    L: wp.vec3            # L plus the medium's emission met on the way
    rng: wp.uint32


@wp.func
def delta_track(media: Media, mi: int, o: wp.vec3, d: wp.vec3, t_max: float, c: int, rng: wp.uint32,
                beta: wp.vec3, r_u: wp.vec3, L: wp.vec3, emit: bool) -> Tracked:
    """The path's next event in medium ``mi`` along o + t d before t_max, sampled with channel c's
    majorant; with ``emit`` the medium's emission sigma_a Le is added at each tentative collision."""
    res = Tracked()
    res.event = PASSED
    res.beta = beta
    res.r_u = r_u
    res.L = L
    f = start_flight(media, mi, o, d, t_max, c, rng)
    while True:
        f = next_collision(media, f)
        if not f.hit:
            break
        T_maj = f.T_maj
        T_c = component(T_maj, c)
        sm = component(f.sigma, c)
        p = o + d * f.t
        mp = properties(media, mi, p)
        if emit and wp.max(mp.Le) > 0.0:
            pdf = sm * T_c
            r_e = wp.cw_mul(res.r_u, wp.cw_mul(f.sigma, T_maj)) / pdf
            if mean3(r_e) > 0.0:
                res.L = res.L + wp.cw_mul(wp.cw_mul(res.beta, T_maj) / pdf, wp.cw_mul(mp.sigma_a, mp.Le)) \
                    / mean3(r_e)
        state = f.rng
        um = wp.randf(state)
        f.rng = state
        p_absorb = component(mp.sigma_a, c) / sm
        if um < p_absorb:
            res.event = ABSORBED
            break
        s_c = component(mp.sigma_s, c)
        if um < p_absorb + s_c / sm:
            pdf = T_c * s_c
            res.beta = wp.cw_mul(res.beta, wp.cw_mul(T_maj, mp.sigma_s)) / pdf
            res.r_u = wp.cw_mul(res.r_u, wp.cw_mul(T_maj, mp.sigma_s)) / pdf
            res.event = SCATTERED
            res.p = p
            break
        sigma_n = wp.max(f.sigma - mp.sigma_a - mp.sigma_s, wp.vec3(0.0))
        pdf = T_c * component(sigma_n, c)
        if pdf <= 0.0:
            res.event = ABSORBED
            break
        res.beta = wp.cw_mul(res.beta, wp.cw_mul(T_maj, sigma_n)) / pdf
        res.r_u = wp.cw_mul(res.r_u, wp.cw_mul(T_maj, sigma_n)) / pdf
        f.T_maj = wp.vec3(1.0)
    if res.event == PASSED:
        # the weight of reaching t_max: T_maj over its probability T_maj[c]
        T_c = component(f.T_maj, c)
        if T_c > 0.0:
            res.beta = wp.cw_mul(res.beta, f.T_maj) / T_c
            res.r_u = wp.cw_mul(res.r_u, f.T_maj) / T_c
        else:
            res.event = ABSORBED
    res.rng = f.rng
    return res


@wp.struct
class Transmitted:
    T: wp.vec3            # the transmittance estimate, per channel
    r: wp.vec3            # the channels' sampling densities over channel c's (multiplied into the path's r_u)
    rng: wp.uint32


@wp.func
def ratio_track(media: Media, mi: int, o: wp.vec3, d: wp.vec3, t_max: float, c: int, rng: wp.uint32,
                T: wp.vec3, r: wp.vec3) -> Transmitted:
    """T and r carried over one more segment, o + t d for t in (0, t_max), of medium ``mi``: ratio
    tracking with channel c's majorant, stopped by Russian roulette once T / mean(r) < 0.05."""
    res = Transmitted()
    res.T = T
    res.r = r
    f = start_flight(media, mi, o, d, t_max, c, rng)
    while True:
        f = next_collision(media, f)
        if not f.hit:
            break
        mp = properties(media, mi, o + d * f.t)
        sigma_n = wp.max(f.sigma - mp.sigma_a - mp.sigma_s, wp.vec3(0.0))
        pdf = component(f.T_maj, c) * component(f.sigma, c)
        res.T = wp.cw_mul(res.T, wp.cw_mul(f.T_maj, sigma_n)) / pdf
        res.r = wp.cw_mul(res.r, wp.cw_mul(f.T_maj, f.sigma)) / pdf
        f.T_maj = wp.vec3(1.0)
        if wp.max(res.T) / wp.max(mean3(res.r), 1.0e-30) < 0.05:
            state = f.rng
            if wp.randf(state) < 0.75:
                res.T = wp.vec3(0.0)
            else:
                res.T = res.T / 0.25
            f.rng = state
        if wp.max(res.T) <= 0.0:
            break
    if wp.max(res.T) > 0.0:
        T_c = component(f.T_maj, c)
        if T_c > 0.0:
            res.T = wp.cw_mul(res.T, f.T_maj) / T_c
            res.r = wp.cw_mul(res.r, f.T_maj) / T_c
        else:
            res.T = wp.vec3(0.0)
    res.rng = f.rng
    return res
