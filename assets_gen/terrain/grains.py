"""Sand grains where the camera can resolve them: one jittered icosphere shape of unit diameter per
mineral class (quartz, feldspar, heavy minerals, shell fragments: sand_minerals) and up to
millions of instances (position, orientation, scale) on the surface mesh it is given.

Diameters are lognormal around 0.35 mm (medium sand); classes are drawn with their number
fractions, and with a ripple map the placement sorts them as wind does (heavy minerals in the
troughs, coarse grains on the crests). Shell fragments are flat and lie flat. The grains sit partly sunk into the surface
and never overlap. Placement follows a weight map painted by the camera: a grain may only go
inside the view frustum, only where a grain of the median diameter covers at least a chosen
fraction of a pixel, and only where the camera sees the surface (the renderer's ray caster tests
occlusion). Each grain keeps the diameter it was drawn with and only its position is redrawn
until it fits, so the placed diameters follow the lognormal exactly.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from assets_gen.core import Generator, GeneratorError, Job, Params, param, reading, require
from assets_gen.core.camera import PinholeCamera
from assets_gen.core.output import write_ply
from assets_gen.terrain.sand_minerals import CLASSES, RipplePhase, acceptance, draw_classes
from renderer.scene.transform import MAX_INSTANCES as MAX_GRAINS


@dataclass(frozen=True)
class GrainParams(Params):
    surface: str = param("assets/dunes/dunes.ply", "surface mesh to scatter on (PLY, +y up, m)", path=True)
    ripples: str = param("", "ripple displacement map (assets-gen ripples) that sorts the grains; none: unsorted",
                         path=True)
    count: int = param(100_000, "number of grains")
    median_diameter_mm: float = param(0.35, "median grain diameter, mm")
    sigma_ln: float = param(0.25, "standard deviation of ln(diameter) (sorting)")
    min_pixel_fraction: float = param(0.25, "least fraction of a pixel a median grain must cover")
    sink_fraction: float = param(0.3, "mean fraction of a grain's diameter below the surface")
    sink_spread: float = param(0.1, "spread (uniform +-) of the sunk fraction")
    shape_jitter: float = param(0.08, "relative radial roughness of the grain shapes")
    elongation: float = param(0.25, "largest relative shortening of a grain shape's axes")
    subdivisions: int = param(2, "icosphere subdivisions of the grain shapes")
    max_rounds: int = param(200, "placement rounds before giving up on grains that do not fit")
    quartz_fraction: float = param(0.80, "number fraction of quartz grains")
    feldspar_fraction: float = param(0.12, "number fraction of feldspar grains")
    heavy_fraction: float = param(0.03, "number fraction of heavy-mineral grains (magnetite, ilmenite)")
    shell_fraction: float = param(0.05, "number fraction of shell fragments")
    heavy_trough_bias: float = param(0.9, "how strongly heavy minerals keep to ripple troughs, 0..1")
    size_crest_bias: float = param(0.6, "how strongly coarse grains keep to ripple crests, 0..1")
    scene: str = param("", "pbrt-v4 scene file to take the camera from (overrides the camera options)",
                       path=True)
    camera_position: tuple[float, float, float] = param((0.0, 0.3, -0.6),
                                                        "camera position, m; y is height above the sand")
    camera_look_at: tuple[float, float, float] = param((0.0, 0.0, 0.3),
                                                       "point looked at, m; y is height above the sand")
    camera_up: tuple[float, float, float] = param((0.0, 1.0, 0.0), "camera up direction")
    fov_deg: float = param(40.0, "field of view on the shorter image axis, degrees")
    width: int = param(1920, "film width, pixels")
    height: int = param(1080, "film height, pixels")

    def validate(self) -> None:
        require(Path(self.surface).is_file(), f"surface mesh {self.surface!r} not found")
        require(not self.scene or Path(self.scene).is_file(), f"scene file {self.scene!r} not found")
        require(1 <= self.count <= MAX_GRAINS, f"grain count must be 1..{MAX_GRAINS} (the renderer's instance limit)")
        require(self.median_diameter_mm > 0, "median grain diameter must be positive (mm)")
        require(0 <= self.sigma_ln <= 1.5, "sigma_ln must be between 0 and 1.5")
        require(0 < self.min_pixel_fraction, "min pixel fraction must be positive")
        require(0 <= self.sink_spread <= self.sink_fraction and self.sink_fraction + self.sink_spread < 0.5,
                "need 0 <= sink spread <= sink fraction and sink fraction + spread < 0.5 "
                "(grain centres stay above the surface)")
        require(0 <= self.shape_jitter < 0.33 and 0 <= self.elongation < 0.66,
                "shape jitter must be in [0, 0.33) and elongation in [0, 0.66) (feldspar takes 1.5x and 1.2x)")
        require(0 <= self.subdivisions <= 5, "subdivisions must be 0..5")
        require(self.max_rounds >= 1, "max rounds must be at least 1")
        require(not self.ripples or Path(self.ripples).is_file(), f"ripple map {self.ripples!r} not found")
        require(0 <= self.heavy_trough_bias <= 1 and 0 <= self.size_crest_bias <= 1,
                "heavy trough bias and size crest bias must be in [0, 1]")
        draw_classes(np.random.default_rng(0), 1, self.fractions())

    def fractions(self) -> tuple[float, float, float, float]:
        return self.quartz_fraction, self.feldspar_fraction, self.heavy_fraction, self.shell_fraction
        require(0 < self.fov_deg < 180, "fov must be between 0 and 180 degrees")
        require(self.width > 0 and self.height > 0, "film resolution must be positive")


def grain_shape(rng: np.random.Generator, subdivisions: int, jitter: float, elongation: float,
                flatness: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(vertices, faces, normals, uvs) of a sand grain of unit diameter (its farthest vertex at
    0.5): an icosphere squashed along random axes, roughened by a few smooth random waves, and
    its y axis scaled by ``flatness`` (a flake lying in the xz plane)."""
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    dirs = sphere.vertices / np.linalg.norm(sphere.vertices, axis=1, keepdims=True)
    axes = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    squash = 1.0 - elongation * rng.random(3)
    waves = rng.standard_normal((6, 3))
    waves /= np.linalg.norm(waves, axis=1, keepdims=True)
    bumps = np.cos(np.pi * rng.uniform(1.0, 3.0, 6) * (dirs @ waves.T) + rng.uniform(0, 2 * np.pi, 6)).mean(1)
    radius = 1.0 + jitter * bumps / max(np.abs(bumps).max(), 1e-12)
    v = (((dirs * radius[:, None]) @ axes) * squash) @ axes.T * np.array([1.0, flatness, 1.0])
    v *= 0.5 / np.linalg.norm(v, axis=1).max()
    mesh = trimesh.Trimesh(v, sphere.faces, process=False)
    uv = np.stack([0.5 + np.arctan2(dirs[:, 2], dirs[:, 0]) / (2 * np.pi),
                   np.arccos(np.clip(dirs[:, 1], -1, 1)) / np.pi], axis=1)
    return v, np.asarray(sphere.faces), np.asarray(mesh.vertex_normals), uv


def random_rotations(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 3, 3) rotations uniform over SO(3) (normalised Gaussian quaternions)."""
    q = rng.standard_normal((n, 4))
    w, x, y, z = (q / np.linalg.norm(q, axis=1, keepdims=True)).T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], axis=1)


def ground_height(vertices: np.ndarray, faces: np.ndarray, xz: np.ndarray) -> np.ndarray:
    """Surface height below each (x, z), by casting rays straight down."""
    from renderer.geometry.raycast import cast_rays

    top = float(vertices[:, 1].max()) + 1.0
    origins = np.column_stack([xz[:, 0], np.full(len(xz), top), xz[:, 1]])
    t = cast_rays(vertices, faces, origins, np.tile([0.0, -1.0, 0.0], (len(xz), 1)))
    require(bool(np.isfinite(t).all()), "camera position or look-at point is not above the surface")
    return top - t


def scene_camera(p: GrainParams, vertices: np.ndarray, faces: np.ndarray) -> PinholeCamera:
    """The scene file's camera, or one from the parameters with heights taken above the sand."""
    if p.scene:
        with reading(p.scene, "scene"):     # the renderer's own located error, as one line of ours
            return PinholeCamera.from_scene(p.scene)
    pos, target = np.array(p.camera_position), np.array(p.camera_look_at)
    ground = ground_height(vertices, faces, np.array([[pos[0], pos[2]], [target[0], target[2]]]))
    pos[1] += ground[0]
    target[1] += ground[1]
    return PinholeCamera.from_look_at(tuple(pos), tuple(target), p.camera_up, p.fov_deg, p.width, p.height)


def visible_triangles(vertices: np.ndarray, faces: np.ndarray, cam: PinholeCamera,
                      max_depth: float) -> np.ndarray:
    """Indices of triangles that may reach into the view frustum cut at ``max_depth``: all of
    them a grain could sit on, and all that could hide one (conservative plane culling)."""
    c = cam.to_camera(vertices)
    planes = cam.frustum_planes(max_depth)
    side = c @ planes[:, :3].T + planes[:, 3]                     # (V, 6), > 0 outside
    outside = (side[faces] > 0).all(axis=1).any(axis=1)
    return np.flatnonzero(~outside)


@dataclass(frozen=True)
class Grains:
    centres: np.ndarray      # (N, 3) m
    diameters: np.ndarray    # (N,) m
    rotations: np.ndarray    # (N, 3, 3)
    kind: np.ndarray         # (N,) uint8: which mineral class (sand_minerals.CLASSES)

    def transforms(self) -> np.ndarray:
        """(N, 4, 4) float32 object-to-world for a unit-diameter grain mesh."""
        m = np.zeros((len(self.centres), 4, 4))
        m[:, :3, :3] = self.rotations * self.diameters[:, None, None]
        m[:, :3, 3] = self.centres
        m[:, 3, 3] = 1.0
        return m.astype(np.float32)


def scatter_grains(vertices: np.ndarray, faces: np.ndarray, cam: PinholeCamera, p: GrainParams,
                   rng: np.random.Generator) -> Grains:
    """Draw every grain's diameter, sinking, orientation and class, then redraw positions for the
    grains that do not yet fit (outside the weight map, hidden, overlapping one already placed,
    or refused by the ripple sorting) until all are placed."""
    from scipy.spatial import cKDTree

    from renderer.geometry.raycast import cast_rays

    n = p.count
    diameters = 1e-3 * p.median_diameter_mm * np.exp(p.sigma_ln * rng.standard_normal(n))
    sink = p.sink_fraction + p.sink_spread * rng.uniform(-1.0, 1.0, n)
    rotations = random_rotations(rng, n)
    kind = draw_classes(rng, n, p.fractions())
    flat = np.flatnonzero([CLASSES[k].flatness < 1 for k in kind])
    rotations[flat] = yaw_rotations(rng, len(flat))                   # flakes lie flat
    radii = 0.5 * diameters
    size_rank = np.log(diameters / (1e-3 * p.median_diameter_mm)) / max(p.sigma_ln, 1e-12)
    phase = RipplePhase(p.ripples) if p.ripples else None

    max_depth = cam.max_depth_for_coverage(1e-3 * p.median_diameter_mm, p.min_pixel_fraction)
    tris = visible_triangles(vertices, faces, cam, max_depth)
    require(len(tris) > 0, "no surface inside the camera frustum where a median grain covers "
                           f"{p.min_pixel_fraction} of a pixel (nearer than {max_depth:.3g} m)")
    sub = faces[tris]
    a, b, c = vertices[sub[:, 0]], vertices[sub[:, 1]], vertices[sub[:, 2]]
    normal = np.cross(b - a, c - a)
    area = 0.5 * np.linalg.norm(normal, axis=1)
    normal /= np.maximum(2.0 * area, 1e-300)[:, None]
    cdf = np.cumsum(area) / area.sum()
    eye = cam.position

    centres = np.zeros((n, 3))
    placed = np.zeros(n, dtype=bool)
    for _ in range(p.max_rounds):
        todo = np.flatnonzero(~placed)
        if len(todo) == 0:
            break
        t = np.minimum(np.searchsorted(cdf, rng.random(len(todo))), len(cdf) - 1)
        r1, r2 = np.sqrt(rng.random(len(todo))), rng.random(len(todo))
        surface = (1 - r1)[:, None] * a[t] + (r1 * (1 - r2))[:, None] * b[t] + (r1 * r2)[:, None] * c[t]
        n_up = normal[t] * np.sign(np.einsum("ij,ij->i", normal[t], eye - surface))[:, None]
        centre = surface + n_up * (radii[todo] * (1.0 - 2.0 * sink[todo]))[:, None]
        ok = cam.in_frustum(centre) & (cam.to_camera(centre)[:, 2] <= max_depth)
        ok &= np.einsum("ij,ij->i", n_up, eye - surface) > 0
        if phase is not None:
            keep = acceptance(phase(centre[:, 0], centre[:, 2]), kind[todo], size_rank[todo],
                              p.heavy_trough_bias, p.size_crest_bias)
            ok &= rng.random(len(todo)) < keep
        ok[ok] = _seen(cast_rays, vertices, sub, eye, centre[ok], radii[todo[ok]])
        fresh = todo[ok]
        centres[fresh] = centre[ok]
        placed[fresh] = True
        placed[_overlapping(cKDTree, centres, radii, placed, fresh)] = False
    missing = int((~placed).sum())
    if missing:
        raise GeneratorError(f"only {n - missing} of {n} grains fit on the visible sand after "
                             f"{p.max_rounds} rounds; lower --count or --min-pixel-fraction")
    return Grains(centres, diameters, rotations, kind)


def yaw_rotations(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 3, 3) rotations about +y by uniform random angles."""
    a = rng.uniform(0.0, 2.0 * np.pi, n)
    c, s_, z, o = np.cos(a), np.sin(a), np.zeros(n), np.ones(n)
    return np.stack([np.stack([c, z, s_], -1), np.stack([z, o, z], -1), np.stack([-s_, z, c], -1)], axis=1)


def _seen(cast_rays: Any, vertices: np.ndarray, faces: np.ndarray, eye: np.ndarray, centres: np.ndarray,
          radii: np.ndarray) -> np.ndarray:
    """Whether the camera's ray towards each grain centre reaches the grain's bounding sphere
    before the surface stops it."""
    if len(centres) == 0:
        return np.zeros(0, dtype=bool)
    d = centres - eye
    dist = np.linalg.norm(d, axis=1)
    hit = cast_rays(vertices, faces, np.broadcast_to(eye, d.shape), d / dist[:, None], max_t=float(dist.max()))
    return hit >= dist - radii


def _overlapping(kdtree: Any, centres: np.ndarray, radii: np.ndarray, placed: np.ndarray,
                 fresh: np.ndarray) -> np.ndarray:
    """The newly placed grains that overlap another placed grain, the later one of each pair losing
    (grains placed in earlier rounds always come first)."""
    if len(fresh) == 0:
        return fresh
    old = np.flatnonzero(placed & ~np.isin(np.arange(len(placed)), fresh))
    order = np.concatenate([old, fresh])
    pairs = kdtree(centres[order]).query_pairs(2.0 * radii.max(), output_type="ndarray")
    i, j = order[pairs[:, 0]], order[pairs[:, 1]]
    clash = np.linalg.norm(centres[i] - centres[j], axis=1) < radii[i] + radii[j]
    later = np.maximum(pairs[clash, 0], pairs[clash, 1])
    return order[np.unique(later)]


def write_grains(stage: Path, grains: Grains, shapes: list[tuple[np.ndarray, ...]], cam: PinholeCamera,
                 preview: bool) -> list[str]:
    """Shapes as ``grain_<class>.ply``; instances all together in ``grains.npz`` (transforms,
    scales = diameters in m, kind = class index) and per class in ``grains_<class>.npz``."""
    names = []
    xf = grains.transforms()
    np.savez(stage / "grains.npz", transforms=xf, scales=grains.diameters.astype(np.float32), kind=grains.kind)
    names.append("grains.npz")
    for k, (cls, shape) in enumerate(zip(CLASSES, shapes)):
        write_ply(stage / f"grain_{cls.name}.ply", *shape[:2], normals=shape[2], uvs=shape[3])
        mine = grains.kind == k
        np.savez(stage / f"grains_{cls.name}.npz", transforms=xf[mine],
                 scales=grains.diameters[mine].astype(np.float32))
        names += [f"grain_{cls.name}.ply", f"grains_{cls.name}.npz"]
    if preview:
        _write_preview(stage / "grains.png", grains, cam)
        names.append("grains.png")
    return names


def _write_preview(path: Path, grains: Grains, cam: PinholeCamera, max_side: int = 480) -> None:
    """The camera's view of where grains landed: brighter where more grains fall in a pixel."""
    from PIL import Image

    scale = max_side / max(cam.width, cam.height)
    w, h = max(1, round(cam.width * scale)), max(1, round(cam.height * scale))
    xy, _ = cam.to_raster(grains.centres)
    ix = np.clip((xy[:, 0] * scale).astype(int), 0, w - 1)
    iy = np.clip((xy[:, 1] * scale).astype(int), 0, h - 1)
    counts = np.bincount(iy * w + ix, minlength=w * h).reshape(h, w)
    img = np.log1p(counts) / max(np.log1p(counts.max()), 1e-12)
    Image.fromarray((img * 255 + 0.5).astype(np.uint8)).save(path, format="PNG")


def generate(p: GrainParams, seed: int) -> tuple[Grains, list[tuple[np.ndarray, ...]], PinholeCamera]:
    """Grain shapes and instances for (parameters, seed)."""
    import trimesh

    p.validate()
    rng = np.random.default_rng(seed)
    with reading(p.surface, "surface mesh"):
        mesh = trimesh.load(p.surface, process=False, force="mesh")
        vertices, faces = np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces)
    require(len(faces) > 0, f"surface mesh {p.surface!r} has no triangles")
    cam = scene_camera(p, vertices, faces)
    grains = scatter_grains(vertices, faces, cam, p, rng)     # first: instances do not shift with the shapes
    shapes = [grain_shape(rng, p.subdivisions, p.shape_jitter * c.jitter, p.elongation * c.elongation, c.flatness)
              for c in CLASSES]
    return grains, shapes, cam


def write(job: Job) -> list[str]:
    grains, shapes, cam = generate(job.params, job.seed)
    return write_grains(job.stage, grains, shapes, cam, job.preview)


GENERATOR = Generator("grains", "sand grains where the camera resolves them: a mineral mix sorted by the ripples",
                      GrainParams, write, __doc__, previews=True)
