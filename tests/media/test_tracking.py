"""Delta tracking, ratio tracking and the media's look-ups against closed forms: Beer-Lambert in
homogeneous media (grey and chromatic, where the channel MIS must stay unbiased in every channel),
optical depths of grids integrated independently in numpy, emission of an absorbing slab, and the
majorant grid bounding the interpolated field."""
from __future__ import annotations

import numpy as np
import pytest
import warp as wp

import renderer.scene  # noqa: F401  (first: renderer.textures and renderer.scene import each other)
from renderer.media.description import MediumDesc
from renderer.media.device import Media, upload_media
from renderer.media.majorants import grid_max
from renderer.media.tracking import ABSORBED, PASSED, SCATTERED, delta_track, properties, ratio_track
from renderer.vecmath import mean3

N = 200_000
DEVICE = "cpu"


@wp.kernel
def _track(media: Media, mi: int, o: wp.vec3, d: wp.vec3, t_max: float, seed: int, emit: int,
           passed: wp.array(dtype=wp.vec3), scattered: wp.array(dtype=wp.vec3), light: wp.array(dtype=wp.vec3),
           trans: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    rng = wp.rand_init(seed, i)
    c = wp.min(int(wp.randf(rng) * 3.0), 2)
    tr = delta_track(media, mi, o, d, t_max, c, rng, wp.vec3(1.0), wp.vec3(1.0), wp.vec3(0.0), emit != 0)
    w = tr.beta / mean3(tr.r_u)
    if tr.event == PASSED:
        passed[i] = w
    if tr.event == SCATTERED:
        scattered[i] = w
    light[i] = tr.L
    rt = ratio_track(media, mi, o, d, t_max, c, tr.rng, wp.vec3(1.0), wp.vec3(1.0))
    trans[i] = rt.T / mean3(rt.r)


def run(m: MediumDesc, o, d, t_max: float, emit: bool = False, seed: int = 1):
    up = upload_media([m], DEVICE)
    outs = [wp.zeros(N, dtype=wp.vec3, device=DEVICE) for _ in range(4)]
    wp.launch(_track, N, [up.struct, 0, wp.vec3(*o), wp.vec3(*d), float(t_max), seed, int(emit), *outs],
              device=DEVICE)
    return [a.numpy().astype(np.float64) for a in outs]


def check_mean(samples: np.ndarray, expected, sigmas: float = 4.5) -> None:
    mean = samples.mean(0)
    err = samples.std(0) / np.sqrt(len(samples)) + 1e-12
    z = np.abs(mean - np.asarray(expected)) / err
    assert np.all(z < sigmas), f"mean {mean} expected {expected} ({z} sigma)"


def homogeneous(sa, ss, Le=(0, 0, 0)) -> MediumDesc:
    return MediumDesc(kind="homogeneous", name="h", sigma_a=np.array(sa, float), sigma_s=np.array(ss, float),
                      Le=np.array(Le, float))


def test_grey_homogeneous_beer_lambert_and_albedo():
    t, st, alb = 0.7, 2.0, 0.75
    passed, scattered, _, trans = run(homogeneous([0.5] * 3, [1.5] * 3), (0, 0, 0), (0, 0, 1), t)
    check_mean(passed, [np.exp(-st * t)] * 3)
    check_mean(scattered, [alb * (1 - np.exp(-st * t))] * 3)
    check_mean(trans, [np.exp(-st * t)] * 3)
    assert np.allclose(passed[passed[:, 0] > 0], 1.0)      # grey: a passing path keeps weight 1


def test_chromatic_homogeneous_is_unbiased_per_channel():
    """Distances sampled with one channel's majorant, weighted by the channels' mean density."""
    t, st = 0.6, np.array([0.5, 2.0, 4.0])
    passed, scattered, _, trans = run(homogeneous([0, 0, 0], st), (1, 2, 3), (0.6, 0, 0.8), t)
    check_mean(passed, np.exp(-st * t))
    check_mean(scattered, 1 - np.exp(-st * t))
    check_mean(trans, np.exp(-st * t))
    wrong = np.exp(-st.mean() * t)
    assert abs(trans[:, 0].mean() - wrong) > 10 * trans[:, 0].std() / np.sqrt(N)


def test_emission_of_an_absorbing_slab():
    """L = Le (1 - exp(-sigma_a t)) along a ray through a purely absorbing, emitting medium."""
    t, sa, Le = 0.9, np.array([0.5, 1.0, 2.0]), np.array([2.0, 1.0, 0.5])
    _, _, light, _ = run(homogeneous(sa, [0, 0, 0], Le), (0, 0, 0), (1, 0, 0), t, emit=True)
    check_mean(light, Le * (1 - np.exp(-sa * t)))


def trilinear(grid: np.ndarray, u: np.ndarray) -> np.ndarray:
    """pbrt's SampledGrid look-up of a (nz, ny, nx[, 3]) grid at points u in [0, 1]^3, written out."""
    nz, ny, nx = grid.shape[:3]
    x = u * np.array([nx, ny, nz]) - 0.5
    i = np.floor(x).astype(int)
    f = x - i
    out = 0.0
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                ix, iy, iz = i[:, 0] + dx, i[:, 1] + dy, i[:, 2] + dz
                inside = (ix >= 0) & (ix < nx) & (iy >= 0) & (iy < ny) & (iz >= 0) & (iz < nz)
                v = grid[np.clip(iz, 0, nz - 1), np.clip(iy, 0, ny - 1), np.clip(ix, 0, nx - 1)]
                v = np.where(inside[:, None] if v.ndim == 2 else inside, v, 0.0)
                wgt = ((f[:, 0] if dx else 1 - f[:, 0]) * (f[:, 1] if dy else 1 - f[:, 1])
                       * (f[:, 2] if dz else 1 - f[:, 2]))
                out = out + (wgt[:, None] if v.ndim == 2 else wgt) * v
    return out


def optical_depth(m: MediumDesc, o, d, t_max, field) -> np.ndarray:
    """Integral of sigma_t along the ray inside the bounds, by the midpoint rule on 200,000 steps, in numpy."""
    n = 200_000
    t = (np.arange(n) + 0.5) * t_max / n
    pw = np.asarray(o) + t[:, None] * np.asarray(d)
    inv = np.linalg.inv(m.medium_to_world)
    pm = pw @ inv[:3, :3].T + inv[:3, 3]
    u = (pm - m.p0) / (m.p1 - m.p0)
    inside = np.all((u >= 0) & (u <= 1), axis=1)        # the medium ends at its bounds, as pbrt's
    return field(u[inside]).sum(0) * t_max / n


def test_uniformgrid_optical_depth_through_a_transformed_grid():
    rng = np.random.default_rng(3)
    dens = rng.random((3, 5, 7)).astype(np.float32)
    xf = np.diag([2.0, 1.0, 1.5, 1.0])
    xf[:3, 3] = [0.5, -0.2, 0.1]
    m = MediumDesc(kind="uniformgrid", name="g", sigma_a=np.array([0.5, 1.0, 1.5]), sigma_s=np.array([1.0, 0.5, 0.3]),
                   density=dens, p0=np.array([-1.0, -1.0, -1.0]), p1=np.array([1.0, 1.0, 1.0]), medium_to_world=xf)
    o, d = np.array([-3.0, -0.5, 0.2]), np.array([0.9, 0.3, 0.1]) / np.linalg.norm([0.9, 0.3, 0.1])
    tau = optical_depth(m, o, d, 6.0, lambda u: trilinear(dens, u)[:, None] * (m.sigma_a + m.sigma_s))
    assert 0.5 < tau.min() and tau.max() < 4      # a test with teeth: neither transparent nor opaque
    passed, scattered, _, trans = run(m, o, d, 6.0)
    check_mean(trans, np.exp(-tau))
    check_mean(passed, np.exp(-tau))


def test_rgbgrid_optical_depth():
    rng = np.random.default_rng(4)
    sa = (rng.random((4, 4, 6, 3)) * 1.5).astype(np.float32)
    ss = (rng.random((4, 4, 6, 3)) * 1.0).astype(np.float32)
    m = MediumDesc(kind="rgbgrid", name="r", rgb_sigma_a=sa, rgb_sigma_s=ss)
    o, d = np.array([0.1, -0.5, 0.3]), np.array([0.2, 1.0, 0.4]) / np.linalg.norm([0.2, 1.0, 0.4])
    tau = optical_depth(m, o, d, 3.0, lambda u: trilinear(sa, u) + trilinear(ss, u))
    passed, _, _, trans = run(m, o, d, 3.0)
    check_mean(trans, np.exp(-tau))
    check_mean(passed, np.exp(-tau))


@wp.kernel
def _sigma_t(media: Media, o: wp.vec3, d: wp.vec3, dt: float, out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    mp = properties(media, 0, o + d * ((float(i) + 0.5) * dt))
    out[i] = mp.sigma_a + mp.sigma_s


def test_cloud_tracking_matches_its_own_density_integrated():
    """The cloud's majorant (sigma_t, density <= 1) and its clipping to the bounds: tracking agrees
    with the optical depth of the device's own density function summed along the ray."""
    m = MediumDesc(kind="cloud", name="c", sigma_a=np.array([0.5] * 3), sigma_s=np.array([2.0] * 3),
                   p0=np.array([0.0, 0.0, 0.0]), p1=np.array([1.0, 1.0, 1.0]))
    o, d, t_max = np.array([-0.5, 0.45, 0.5]), np.array([1.0, 0.0, 0.0]), 2.0
    up = upload_media([m], DEVICE)
    n = 100_000
    out = wp.zeros(n, dtype=wp.vec3, device=DEVICE)
    wp.launch(_sigma_t, n, [up.struct, wp.vec3(*o), wp.vec3(*d), t_max / n, out], device=DEVICE)
    tau = out.numpy().astype(np.float64).sum(0) * t_max / n
    assert 0.3 < tau[0] < 2.5
    _, _, _, trans = run(m, o, d, t_max)
    check_mean(trans, np.exp(-tau))


def test_majorant_grid_bounds_the_interpolated_field():
    rng = np.random.default_rng(5)
    g = (rng.random((9, 20, 13)) ** 4).astype(np.float32)
    cells = 4
    bound = grid_max(g, cells)
    u = rng.random((200_000, 3))
    v = trilinear(g, u)
    c = np.minimum((u * cells).astype(int), cells - 1)
    assert np.all(v <= bound[c[:, 2], c[:, 1], c[:, 0]] + 1e-6)
    assert bound.max() == g.max()


def test_nanovdb_file_read_by_warp(tmp_path):
    """A NanoVDB file (written by Warp from a dense grid at a world offset and voxel size) tracked
    against the optical depth of the same grid interpolated in numpy, inside the grid's world
    bounding box (index 0 to n: below the first voxel centre there is no medium, as in pbrt-v4)."""
    from pathlib import Path

    rng = np.random.default_rng(6)
    g = rng.random((6, 5, 4)).astype(np.float32)       # [x, y, z]
    origin, voxel = np.array([1.0, 2.0, 3.0]), 0.5
    wp.Volume.load_from_numpy(g, min_world=tuple(origin), voxel_size=voxel, bg_value=0.0,
                              device=DEVICE).save_to_nvdb(str(tmp_path / "g.nvdb"))
    m = MediumDesc(kind="nanovdb", name="n", filename=Path(tmp_path / "g.nvdb"), sigma_a=np.array([0.5, 1.0, 2.0]),
                   sigma_s=np.array([1.0, 1.0, 1.0]))
    o, d = np.array([0.0, 3.1, 4.0]), np.array([1.0, 0.1, 0.05]) / np.linalg.norm([1.0, 0.1, 0.05])
    n = 200_000
    t = (np.arange(n) + 0.5) * 6.0 / n
    idx = (o + t[:, None] * d - origin) / voxel          # index space: voxel centres at integers
    dens = trilinear(np.ascontiguousarray(g.transpose(2, 1, 0)), (idx + 0.5) / np.array([6, 5, 4]))
    dens = np.where(np.all(idx >= 0, axis=1), dens, 0.0)   # the medium ends at the grid's world box, as pbrt's
    tau = dens.sum() * 6.0 / n * (m.sigma_a + m.sigma_s)
    assert 0.5 < tau.min() and tau.max() < 5
    passed, _, _, trans = run(m, o, d, 6.0)
    check_mean(trans, np.exp(-tau))
    check_mean(passed, np.exp(-tau))


def test_temperature_grid_emits_pbrts_peak_normalised_blackbody():
    """A purely absorbing uniformgrid at 1600 K: L = the integral of sigma_a(t) tent(t) blackbody(T'(t))
    exp(-tau(t)), with T' = (T - offset) scale (3000 K where the grid is not interpolated against the
    zeros outside it) and pbrt's default Lescale tent."""
    from renderer.media.blackbody import SIZE, T_MAX, T_MIN, blackbody_table

    dens = np.array([[[0.5, 1.0], [1.5, 0.8]], [[1.2, 0.4], [0.9, 1.1]]], np.float32)
    m = MediumDesc(kind="uniformgrid", name="t", sigma_a=np.array([0.6, 0.6, 0.6]), sigma_s=np.zeros(3),
                   density=dens, temperature=np.full((2, 2, 2), 1600.0, np.float32), temperature_offset=100.0,
                   temperature_scale=2.0)
    o, d, t_max = np.array([-0.5, 0.4, 0.55]), np.array([1.0, 0.0, 0.0]), 2.0
    n = 200_000
    t = (np.arange(n) + 0.5) * t_max / n
    u = o + t[:, None] * d
    inside = np.all((u >= 0) & (u <= 1), axis=1)
    sa = np.where(inside, 0.6 * trilinear(dens, u), 0.0)
    tent = np.where(inside, np.prod(1 - np.abs(u - 0.5), axis=1), 0.0)
    tau = np.cumsum(sa) * t_max / n
    hot = (np.where(inside, trilinear(m.temperature, u), 0.0) - 100.0) * 2.0
    temps = T_MIN * (T_MAX / T_MIN) ** (np.arange(SIZE) / (SIZE - 1))
    table = blackbody_table()
    colour = np.stack([np.interp(np.log(np.maximum(hot, 1.0)), np.log(temps), table[:, k]) for k in range(3)], -1)
    colour[hot <= 100.0] = 0.0
    assert colour[:, 0].max() > 3 * colour[:, 2].max() > 0          # a 3000 K glow: red
    expected = ((sa * tent * np.exp(-tau))[:, None] * colour).sum(0) * t_max / n
    _, _, light, _ = run(m, o, d, t_max, emit=True)
    check_mean(light, expected)
