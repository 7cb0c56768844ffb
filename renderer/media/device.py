"""Media on the device: one :class:`Media` struct of arrays indexed by medium, with grids as
``wp.Volume`` (NanoVDB, sampled the same way on the CPU and CUDA) and majorant grids for tracking.

pbrt's dense grids (``uniformgrid``, ``rgbgrid``) become volumes in index space: sample (x, y, z) is
voxel (x, y, z), Warp's trilinear ``volume_sample`` interpolates between voxel centres and gives
the background 0 outside, which is exactly pbrt-v4's SampledGrid::Lookup at index p * n - 0.5.
A ``nanovdb`` file is read by Warp itself; its values are looked up at the file's own index
coordinates. A scene without media uploads a one-entry stand-in that no kernel reads."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import warp as wp

from renderer.errors import SceneError
from renderer.media.blackbody import SIZE, T_MAX, T_MIN, blackbody_table
from renderer.media.description import KINDS, MediumDesc
from renderer.media.majorants import majorants
from renderer.textures.noise import permutation

HOMOGENEOUS, UNIFORMGRID, RGBGRID, CLOUD, NANOVDB = (wp.constant(KINDS.index(k)) for k in KINDS)
#: volume slots per medium: uniformgrid (density, Lescale, default Lescale, temperature), rgbgrid
#: (sigma_a, sigma_s, Le), nanovdb (density)
SLOTS = 4
#: the blackbody table's log-temperature axis
LOG_T_MIN = wp.constant(float(np.log(T_MIN)))
LOG_T_STEP = wp.constant(float(np.log(T_MAX / T_MIN) / (SIZE - 1)))
TABLE_LAST = wp.constant(SIZE - 1)


@wp.struct
class Media:
    count: int
    kind: wp.array(dtype=int)
    to_medium: wp.array(dtype=wp.mat44)      # world -> the medium's own space
    lo: wp.array(dtype=wp.vec3)              # grid / cloud bounds in medium space (nanovdb: index space)
    hi: wp.array(dtype=wp.vec3)
    res: wp.array(dtype=wp.vec3)             # grid samples per axis (nx, ny, nz)
    sigma_a: wp.array(dtype=wp.vec3)         # times the density (grids: where a grid is not given)
    sigma_s: wp.array(dtype=wp.vec3)
    Le: wp.array(dtype=wp.vec3)
    g: wp.array(dtype=float)
    vol: wp.array2d(dtype=wp.uint64)         # [medium, slot] volume ids, 0 where a grid is not given
    cloud: wp.array(dtype=wp.vec3)           # density, wispiness, frequency
    maj_first: wp.array(dtype=int)           # each medium's first cell in ``maj``
    maj_res: wp.array(dtype=wp.vec3i)        # its majorant grid's cells per axis
    maj: wp.array(dtype=wp.vec3)             # per cell, a bound of sigma_t per channel
    perm: wp.array(dtype=int)                # Perlin noise permutation (the cloud)
    temperature: wp.array(dtype=wp.vec2)     # a temperature grid's offset and scale
    blackbody: wp.array(dtype=wp.vec3)       # renderer.media.blackbody's table (1 entry unless used)


@dataclass
class MediaUpload:
    struct: Media
    keep: list = field(default_factory=list)     # the volumes and arrays the struct points into


def _volume(grid: np.ndarray | None, device: str) -> wp.Volume | None:
    """A (nz, ny, nx[, 3]) grid as a volume whose voxel (x, y, z) holds sample [z, y, x]."""
    if grid is None:
        return None
    a = np.ascontiguousarray(np.moveaxis(grid, (0, 1, 2), (2, 1, 0)), dtype=np.float32)
    return wp.Volume.load_from_numpy(a, bg_value=(0.0, 0.0, 0.0) if a.ndim == 4 else 0.0, device=device)


def _nanovdb(m: MediumDesc, device: str) -> tuple[wp.Volume, np.ndarray, np.ndarray, float]:
    """The file's grid named ``m.grid_name`` (the first if no grid has a name), its index-space
    bounds and the largest value of its active voxels."""
    with open(m.filename, "rb") as f:
        vol = wp.Volume.load_from_nvdb(f, device=device)
    first = vol
    while vol is not None and vol.get_grid_info().name not in (m.grid_name, ""):
        vol = vol.load_next_grid()
    vol = vol or first
    if vol.dtype != wp.float32:
        raise SceneError(f'{m.filename}: grid "{m.grid_name}" holds {vol.dtype.__name__}, not float densities', m.loc)
    ijk = vol.get_voxels().numpy()
    if len(ijk) == 0:
        raise SceneError(f"{m.filename}: the density grid has no active voxels", m.loc)
    values = wp.zeros(len(ijk), dtype=float, device=device)
    wp.launch(_lookup, len(ijk), [vol.id, wp.array(ijk, dtype=wp.vec3i, device=device), values], device=device)
    v = values.numpy()
    if not np.all(np.isfinite(v)) or np.any(v < 0.0):
        raise SceneError(f"{m.filename}: the density grid holds NaN or negative values", m.loc)
    lo, hi = _index_bounds(vol)
    return vol, lo, hi, float(v.max())


#: where NanoVDB's GridData keeps the grid's world bounding box (six float64 after the magic,
#: checksum, version, flags, index, count, size, a 256-byte name and the 264-byte map)
_WORLD_BBOX = 40 + 256 + 264


def _index_bounds(vol: wp.Volume) -> tuple[np.ndarray, np.ndarray]:
    """The grid's world bounding box in its index space: where pbrt-v4's medium ends."""
    header = vol.array().numpy()[:_WORLD_BBOX + 48].copy() if vol.device.is_cpu else vol.array()[:_WORLD_BBOX + 48].numpy()
    box = np.frombuffer(header[_WORLD_BBOX:_WORLD_BBOX + 48].tobytes(), np.float64).reshape(2, 3)
    info = vol.get_grid_info()
    m = np.array(info.transform_matrix, np.float64).reshape(3, 3)
    t = np.array(info.translation, np.float64)
    corners = np.array([[box[i, 0], box[j, 1], box[k, 2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    idx = (corners - t) @ np.linalg.inv(m).T
    return idx.min(0), idx.max(0)


@wp.kernel
def _lookup(vid: wp.uint64, ijk: wp.array(dtype=wp.vec3i), out: wp.array(dtype=float)):
    i = wp.tid()
    c = ijk[i]
    out[i] = wp.volume_lookup_f(vid, c[0], c[1], c[2])


def upload_media(media: list[MediumDesc], device: str) -> MediaUpload:
    n = max(len(media), 1)
    ms = media or [MediumDesc(kind="homogeneous", name="")]
    vols = np.zeros((n, SLOTS), np.uint64)
    keep: list = []
    firsts, ress, cells = [], [], []
    lo = np.zeros((n, 3), np.float32)
    hi = np.ones((n, 3), np.float32)
    res = np.ones((n, 3), np.float32)
    for i, m in enumerate(ms):
        lo[i], hi[i] = m.p0, m.p1
        if m.kind == "nanovdb":
            vol, lo[i], hi[i], vmax = _nanovdb(m, device)
            grids = [vol]
            cres, cell = (1, 1, 1), ((m.sigma_a + m.sigma_s) * vmax).reshape(1, 3).astype(np.float32)
        else:
            if m.kind == "uniformgrid":
                # slot 1 the Lescale grid; without one, slot 2 pbrt's default, a 1x1x1 grid of 1
                ones = np.ones((1, 1, 1), np.float32)
                grids = [_volume(m.density, device), _volume(m.le_scale_grid, device),
                         _volume(ones, device) if m.le_scale_grid is None else None, _volume(m.temperature, device)]
                res[i] = m.density.shape[::-1]
            elif m.kind == "rgbgrid":
                grids = [_volume(g, device) for g in (m.rgb_sigma_a, m.rgb_sigma_s, m.rgb_Le)]
                shape = next(g for g in (m.rgb_sigma_a, m.rgb_sigma_s) if g is not None).shape
                res[i] = shape[2::-1]
            else:
                grids = []
            cres, cell = majorants(m)
        for j, v in enumerate(grids):
            if v is not None:
                vols[i, j] = v.id
                keep.append(v)
        firsts.append(sum(len(c) for c in cells))
        ress.append(cres)
        cells.append(cell)
    S = Media()
    S.count = len(media)
    S.kind = wp.array(np.array([KINDS.index(m.kind) for m in ms], np.int32), dtype=int, device=device)
    S.to_medium = wp.array(np.stack([np.linalg.inv(m.medium_to_world) for m in ms]).astype(np.float32),
                           dtype=wp.mat44, device=device)
    S.lo = wp.array(lo, dtype=wp.vec3, device=device)
    S.hi = wp.array(hi, dtype=wp.vec3, device=device)
    S.res = wp.array(res, dtype=wp.vec3, device=device)
    S.sigma_a = wp.array(np.stack([m.sigma_a for m in ms]).astype(np.float32), dtype=wp.vec3, device=device)
    S.sigma_s = wp.array(np.stack([m.sigma_s for m in ms]).astype(np.float32), dtype=wp.vec3, device=device)
    S.Le = wp.array(np.stack([m.Le for m in ms]).astype(np.float32), dtype=wp.vec3, device=device)
    S.g = wp.array(np.array([m.g for m in ms], np.float32), dtype=float, device=device)
    S.vol = wp.array(vols, dtype=wp.uint64, device=device)
    S.cloud = wp.array(np.array([m.cloud for m in ms], np.float32), dtype=wp.vec3, device=device)
    S.maj_first = wp.array(np.array(firsts, np.int32), dtype=int, device=device)
    S.maj_res = wp.array(np.array(ress, np.int32), dtype=wp.vec3i, device=device)
    S.maj = wp.array(np.concatenate(cells), dtype=wp.vec3, device=device)
    has_cloud = any(m.kind == "cloud" for m in media)
    S.perm = wp.array(permutation() if has_cloud else np.zeros(1, np.int32), dtype=int, device=device)
    S.temperature = wp.array(np.array([(m.temperature_offset, m.temperature_scale) for m in ms], np.float32),
                             dtype=wp.vec2, device=device)
    hot = any(m.temperature is not None for m in media)
    S.blackbody = wp.array(blackbody_table() if hot else np.zeros((1, 3), np.float32), dtype=wp.vec3, device=device)
    keep += [S.temperature, S.blackbody, S.kind, S.to_medium, S.lo, S.hi, S.res, S.sigma_a, S.sigma_s, S.Le, S.g, S.vol, S.cloud, S.maj_first,
             S.maj_res, S.maj, S.perm]
    return MediaUpload(S, keep)
