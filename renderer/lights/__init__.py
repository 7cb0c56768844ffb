"""Light sources: an infinite light (constant or image, importance sampled), distant lights (a
delta direction or a soft cone, e.g. the sun), and diffuse area lights on triangle meshes.

Next-event estimation picks one light uniformly; every ``*_pdf`` here is the solid-angle density
of that light's own sampling, so the integrator can weight BSDF-sampled hits with MIS.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import warp as wp

from renderer.sampling.equal_area import equal_area_sphere_to_square, equal_area_square_to_sphere
from renderer.sampling.distribution import distribution_2d, sample_cdf
from renderer.errors import SceneError
from renderer.vecmath import PI
from renderer.sampling.frames import frame_from_normal, to_world
from renderer.sampling.warps import uniform_cone

ENV = 0
DISTANT = 1
AREA = 2
MAP_CONSTANT = 0
MAP_EQUAL_AREA = 1
MAP_LATLONG = 2


@wp.struct
class Lights:
    count: int
    kind: wp.array(dtype=int)
    L: wp.array(dtype=wp.vec3)             # radiance (area, env multiplier) or irradiance (distant)
    direction: wp.array(dtype=wp.vec3)     # distant: unit vector towards the light
    cos_max: wp.array(dtype=float)         # distant: cone half-angle cosine (1 = delta)
    two_sided: wp.array(dtype=int)
    tri_start: wp.array(dtype=int)         # area: first triangle and count in the tri_* arrays
    tri_count: wp.array(dtype=int)
    area: wp.array(dtype=float)            # area: total world-space area
    tri_p: wp.array(dtype=wp.vec3)         # 3 world-space vertices per triangle
    tri_cdf: wp.array(dtype=float)         # per area light: tri_count + 1 entries from cdf_start
    cdf_start: wp.array(dtype=int)
    env: int                               # index of the infinite light, -1 if none
    env_mapping: int
    env_size: wp.vec2i
    env_pixels: wp.array(dtype=wp.vec3)
    env_cond: wp.array(dtype=float)        # (h, w + 1) conditional CDFs, flattened
    env_marg: wp.array(dtype=float)        # h + 1
    env_integral: float
    env_to_world: wp.mat33
    world_to_env: wp.mat33


@wp.struct
class LightSample:
    wi: wp.vec3
    L: wp.vec3
    pdf: float                             # solid angle, including the light-selection probability
    dist: float                            # distance to the sampled point (inf-like for env/distant)
    delta: bool


# ---- infinite light ---------------------------------------------------------------------------





@wp.func
def _env_uv(lights: Lights, w_light: wp.vec3) -> wp.vec2:
    if lights.env_mapping == MAP_EQUAL_AREA:
        return equal_area_sphere_to_square(w_light)
    theta = wp.acos(wp.clamp(w_light[2], -1.0, 1.0))
    phi = wp.atan2(w_light[1], w_light[0])
    if phi < 0.0:
        phi = phi + 2.0 * PI
    return wp.vec2(phi / (2.0 * PI), theta / PI)


@wp.func
def _env_pixel(lights: Lights, uv: wp.vec2) -> int:
    w = lights.env_size[0]
    h = lights.env_size[1]
    x = wp.clamp(int(uv[0] * float(w)), 0, w - 1)
    y = wp.clamp(int(uv[1] * float(h)), 0, h - 1)
    return y * w + x


@wp.func
def _env_jacobian(lights: Lights, w_light: wp.vec3) -> float:
    """Solid angle per unit of (u, v): 4π for the equal-area map, 2π² sin θ for lat-long."""
    if lights.env_mapping == MAP_EQUAL_AREA:
        return 4.0 * PI
    return 2.0 * PI * PI * wp.sqrt(wp.max(0.0, 1.0 - w_light[2] * w_light[2]))


@wp.func
def env_radiance(lights: Lights, d: wp.vec3) -> wp.vec3:
    """Radiance arriving along -d from the infinite light (d points away from the scene)."""
    i = lights.env
    if i < 0:
        return wp.vec3(0.0)
    if lights.env_mapping == MAP_CONSTANT:
        return lights.L[i]
    w = wp.normalize(lights.world_to_env * d)
    return wp.cw_mul(lights.L[i], lights.env_pixels[_env_pixel(lights, _env_uv(lights, w))])


@wp.func
def env_pdf(lights: Lights, d: wp.vec3) -> float:
    """Solid-angle density of sampling direction d from the infinite light (selection excluded)."""
    if lights.env_mapping == MAP_CONSTANT:
        return 1.0 / (4.0 * PI)
    w = wp.normalize(lights.world_to_env * d)
    jac = _env_jacobian(lights, w)
    if jac <= 0.0:
        return 0.0
    uv = _env_uv(lights, w)
    wdt = lights.env_size[0]
    hgt = lights.env_size[1]
    x = wp.clamp(int(uv[0] * float(wdt)), 0, wdt - 1)
    y = wp.clamp(int(uv[1] * float(hgt)), 0, hgt - 1)
    row = y * (wdt + 1)
    f = (lights.env_cond[row + x + 1] - lights.env_cond[row + x]) * float(wdt)
    fy = (lights.env_marg[y + 1] - lights.env_marg[y]) * float(hgt)
    return f * fy / jac


@wp.func
def _sample_env(lights: Lights, u: wp.vec2) -> LightSample:
    s = LightSample()
    s.delta = False
    s.dist = 1.0e30
    if lights.env_mapping == MAP_CONSTANT:
        # uniform sphere: the constant sky has no preferred direction
        z = 1.0 - 2.0 * u[0]
        r = wp.sqrt(wp.max(0.0, 1.0 - z * z))
        phi = 2.0 * PI * u[1]
        s.wi = wp.vec3(r * wp.cos(phi), r * wp.sin(phi), z)
        s.L = lights.L[lights.env]
        s.pdf = 1.0 / (4.0 * PI)
        return s
    wdt = lights.env_size[0]
    hgt = lights.env_size[1]
    vy = sample_cdf(lights.env_marg, 0, hgt, u[1])
    y = int(vy[1])
    ux = sample_cdf(lights.env_cond, y * (wdt + 1), wdt, u[0])
    uv = wp.vec2(ux[0], vy[0])
    w = wp.vec3(0.0)
    if lights.env_mapping == MAP_EQUAL_AREA:
        w = equal_area_square_to_sphere(uv)
    else:
        theta = uv[1] * PI
        phi = uv[0] * 2.0 * PI
        w = wp.vec3(wp.sin(theta) * wp.cos(phi), wp.sin(theta) * wp.sin(phi), wp.cos(theta))
    s.wi = wp.normalize(lights.env_to_world * w)
    s.L = env_radiance(lights, s.wi)
    s.pdf = env_pdf(lights, s.wi)
    return s


# ---- distant and area lights ------------------------------------------------------------------

@wp.func
def distant_cone_radiance(lights: Lights, i: int, d: wp.vec3) -> wp.vec3:
    """Radiance seen along d inside a soft distant light's cone (zero for delta lights)."""
    cm = lights.cos_max[i]
    if cm >= 1.0 or wp.dot(d, lights.direction[i]) < cm:
        return wp.vec3(0.0)
    return lights.L[i] / (2.0 * PI * (1.0 - cm))


@wp.func
def area_pdf(lights: Lights, i: int, p_ref: wp.vec3, p_light: wp.vec3, n_light: wp.vec3) -> float:
    """Solid-angle density at p_ref of area-sampling light i at p_light (selection excluded)."""
    d = p_light - p_ref
    dist2 = wp.dot(d, d)
    c = wp.abs(wp.dot(n_light, d)) / wp.sqrt(dist2)
    if c <= 0.0:
        return 0.0
    return dist2 / (c * lights.area[i])


@wp.func
def area_emitted(lights: Lights, i: int, n_light: wp.vec3, w_out: wp.vec3) -> wp.vec3:
    """Radiance leaving an area light with normal n_light in direction w_out."""
    if lights.two_sided[i] == 0 and wp.dot(n_light, w_out) <= 0.0:
        return wp.vec3(0.0)
    return lights.L[i]


@wp.func
def sample_light(lights: Lights, p: wp.vec3, u_select: float, u: wp.vec2) -> LightSample:
    """Pick one light uniformly and sample a direction towards it from p."""
    n = lights.count
    i = wp.min(int(u_select * float(n)), n - 1)
    sel = 1.0 / float(n)
    k = lights.kind[i]
    s = LightSample()
    if k == ENV:
        s = _sample_env(lights, u)
    elif k == DISTANT:
        cm = lights.cos_max[i]
        s.dist = 1.0e30
        if cm >= 1.0:
            s.wi = lights.direction[i]
            s.L = lights.L[i]
            s.pdf = 1.0
            s.delta = True
        else:
            s.wi = to_world(frame_from_normal(lights.direction[i]), uniform_cone(u, cm))
            s.L = lights.L[i] / (2.0 * PI * (1.0 - cm))
            s.pdf = 1.0 / (2.0 * PI * (1.0 - cm))
            s.delta = False
    else:
        start = lights.tri_start[i]
        cnt = lights.tri_count[i]
        tv = sample_cdf(lights.tri_cdf, lights.cdf_start[i], cnt, u[0])
        t = start + int(tv[1])
        # reuse the remainder of u[0] within the chosen triangle's CDF cell
        u0 = tv[0] * float(cnt) - tv[1]
        su = wp.sqrt(wp.clamp(u0, 0.0, 1.0))
        b0 = 1.0 - su
        b1 = u[1] * su
        a = lights.tri_p[3 * t]
        b = lights.tri_p[3 * t + 1]
        c = lights.tri_p[3 * t + 2]
        q = a * b0 + b * b1 + c * (1.0 - b0 - b1)
        nl = wp.normalize(wp.cross(b - a, c - a))
        d = q - p
        dist = wp.length(d)
        s.delta = False
        if dist <= 0.0:
            s.pdf = 0.0
            return s
        s.wi = d / dist
        s.dist = dist
        s.L = area_emitted(lights, i, nl, -s.wi)
        s.pdf = area_pdf(lights, i, p, q, nl)
    s.pdf = s.pdf * sel
    return s


# ---- host side --------------------------------------------------------------------------------

@dataclass
class LightTable:
    """Host-side light list; ``upload`` turns it into the :class:`Lights` struct."""

    kind: list[int] = field(default_factory=list)
    L: list[np.ndarray] = field(default_factory=list)
    direction: list[np.ndarray] = field(default_factory=list)
    cos_max: list[float] = field(default_factory=list)
    two_sided: list[int] = field(default_factory=list)
    tri_start: list[int] = field(default_factory=list)
    tri_count: list[int] = field(default_factory=list)
    area: list[float] = field(default_factory=list)
    tris: list[np.ndarray] = field(default_factory=list)
    cdfs: list[np.ndarray] = field(default_factory=list)
    n_tris: int = 0
    env: int = -1
    env_mapping: int = MAP_CONSTANT
    env_image: np.ndarray | None = None
    env_to_world: np.ndarray = field(default_factory=lambda: np.eye(3))

    def _add(self, kind, L, direction=(0, 0, 1), cos_max=1.0, two_sided=0, tri_start=0, tri_count=0, area=0.0) -> int:
        self.kind.append(kind)
        self.L.append(np.asarray(L, dtype=np.float32))
        self.direction.append(np.asarray(direction, dtype=np.float32))
        self.cos_max.append(float(cos_max))
        self.two_sided.append(int(two_sided))
        self.tri_start.append(tri_start)
        self.tri_count.append(tri_count)
        self.area.append(float(area))
        if kind != AREA:
            self.cdfs.append(np.zeros(1, dtype=np.float32))
        return len(self.kind) - 1

    def add_infinite(self, L: np.ndarray, image: np.ndarray | None, light_to_world: np.ndarray, loc) -> int:
        if self.env >= 0:
            raise SceneError("only one infinite light is supported per scene", loc)
        R = np.asarray(light_to_world, dtype=np.float64)[:3, :3]
        self.env_to_world = R
        if image is not None:
            h, w = image.shape[:2]
            if w == h:
                self.env_mapping = MAP_EQUAL_AREA
            elif w == 2 * h:
                self.env_mapping = MAP_LATLONG
            else:
                raise SceneError(f"environment image must be square (equal-area) or 2:1 (lat-long), got {w}x{h}", loc)
            rgb = image[..., :3] if image.shape[2] >= 3 else np.repeat(image[..., :1], 3, axis=2)
            if not np.all(np.isfinite(rgb)) or np.any(rgb < 0):
                raise SceneError("environment image contains negative, NaN or infinite values", loc)
            self.env_image = np.ascontiguousarray(rgb, dtype=np.float32)
        self.env = self._add(ENV, L)
        return self.env

    def add_distant(self, direction: np.ndarray, L: np.ndarray, angular_radius_deg: float) -> int:
        d = np.asarray(direction, dtype=np.float64)
        return self._add(DISTANT, L, d / np.linalg.norm(d), np.cos(np.radians(angular_radius_deg)))

    def add_area(self, tris: np.ndarray, L: np.ndarray, two_sided: bool) -> int:
        """tris: (T, 3, 3) world-space triangles with outward winding."""
        areas = 0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
        total = float(areas.sum())
        keep = areas > 0
        tris, areas = tris[keep], areas[keep]
        if total <= 0 or len(tris) == 0:
            return -1
        cdf = np.concatenate([[0.0], np.cumsum(areas) / total]).astype(np.float32)
        cdf[-1] = 1.0
        i = self._add(AREA, L, two_sided=two_sided, tri_start=self.n_tris, tri_count=len(tris), area=total)
        self.tris.append(np.asarray(tris, dtype=np.float32).reshape(-1, 3))
        self.cdfs.append(cdf)
        self.n_tris += len(tris)
        return i

    def env_distribution_function(self) -> np.ndarray:
        """The function the env map is importance sampled by: max channel, times sin θ for lat-long."""
        img = self.env_image
        f = img.max(axis=2).astype(np.float64)
        if self.env_mapping == MAP_LATLONG:
            h = img.shape[0]
            f = f * np.sin(np.pi * (np.arange(h) + 0.5) / h)[:, None]
        return f

    def upload(self, device: str) -> tuple[Lights, list]:
        S = Lights()
        n = len(self.kind)
        S.count = n
        z3 = np.zeros((1, 3), np.float32)
        arr = lambda a, dt: wp.array(a, dtype=dt, device=device)
        S.kind = arr(np.asarray(self.kind or [0], np.int32), int)
        S.L = arr(np.asarray(self.L, np.float32).reshape(-1, 3) if n else z3, wp.vec3)
        S.direction = arr(np.asarray(self.direction, np.float32).reshape(-1, 3) if n else z3, wp.vec3)
        S.cos_max = arr(np.asarray(self.cos_max or [1.0], np.float32), float)
        S.two_sided = arr(np.asarray(self.two_sided or [0], np.int32), int)
        S.tri_start = arr(np.asarray(self.tri_start or [0], np.int32), int)
        S.tri_count = arr(np.asarray(self.tri_count or [0], np.int32), int)
        S.area = arr(np.asarray(self.area or [0.0], np.float32), float)
        S.tri_p = arr(np.concatenate(self.tris) if self.tris else z3, wp.vec3)
        cdf_all = np.concatenate(self.cdfs) if self.cdfs else np.zeros(1, np.float32)
        S.tri_cdf = arr(cdf_all.astype(np.float32), float)
        starts = np.concatenate([[0], np.cumsum([len(c) for c in self.cdfs])[:-1]]) if self.cdfs else [0]
        S.cdf_start = arr(np.asarray(starts, np.int32), int)
        S.env = self.env
        S.env_mapping = self.env_mapping
        R = self.env_to_world
        S.env_to_world = wp.mat33(*R.astype(np.float32).ravel())
        S.world_to_env = wp.mat33(*np.linalg.inv(R).astype(np.float32).ravel())
        if self.env_image is not None:
            h, w = self.env_image.shape[:2]
            cond, marg, integral = distribution_2d(self.env_distribution_function())
            S.env_size = wp.vec2i(w, h)
            S.env_pixels = arr(self.env_image.reshape(-1, 3), wp.vec3)
            S.env_cond = arr(cond.ravel(), float)
            S.env_marg = arr(marg, float)
            S.env_integral = integral
        else:
            S.env_size = wp.vec2i(1, 1)
            S.env_pixels = arr(z3, wp.vec3)
            S.env_cond = arr(np.array([0.0, 1.0], np.float32), float)
            S.env_marg = arr(np.array([0.0, 1.0], np.float32), float)
            S.env_integral = 1.0
        keep = [S.kind, S.L, S.direction, S.cos_max, S.two_sided, S.tri_start, S.tri_count, S.area, S.tri_p,
                S.tri_cdf, S.cdf_start, S.env_pixels, S.env_cond, S.env_marg]
        return S, keep
