"""Textures on the device: one table of records (constant, image, checkerboard) and one pool of
image pixels. Every material parameter is a texture id, so constants and maps share one path.
Image and checkerboard records map the hit to texture coordinates with pbrt-v4's 2D mappings:
the surface's uv, or spherical/cylindrical/planar from the world-space point. pbrt's mix,
directionmix and scale-of-two-textures combine up to three other records; those inputs must be
plain records (constant, image, checkerboard), as Warp functions cannot recurse."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import warp as wp

from renderer.errors import SceneError
from renderer.scene.description import TextureDesc, find_texture
from renderer.scene.texture_params import MAPPINGS, WRAP, read_texture

CONSTANT = 0
IMAGE = 1
CHECKERBOARD = 2
MIX = 3
DIRECTION_MIX = 4
PRODUCT = 5
UV, SPHERICAL, CYLINDRICAL, PLANAR = (MAPPINGS[k] for k in ("uv", "spherical", "cylindrical", "planar"))


@wp.struct
class Textures:
    kind: wp.array(dtype=int)
    scale: wp.array(dtype=wp.vec3)      # constant value, or multiplier of an image / checker tex1
    alt: wp.array(dtype=wp.vec3)        # checkerboard tex2; directionmix: the world direction
    inputs: wp.array(dtype=wp.vec3i)    # mix (tex1, tex2, amount), directionmix (tex1, tex2), product (a, b)
    uvmap: wp.array(dtype=wp.vec4)      # (su, sv, du, dv): st = (su u + du, sv v + dv)
    mapping: wp.array(dtype=int)        # UV, SPHERICAL, CYLINDRICAL or PLANAR
    xform: wp.array(dtype=wp.mat44)     # texture-from-world (planar: rows v1, v2 folded in)
    image: wp.array(dtype=wp.vec4i)     # (pixel offset, width, height, wrap mode)
    pixels: wp.array(dtype=wp.vec3)


@wp.func
def _texel(T: Textures, img: wp.vec4i, x: int, y: int) -> wp.vec3:
    w = img[1]
    h = img[2]
    if img[3] == 0:
        x = ((x % w) + w) % w
        y = ((y % h) + h) % h
    elif img[3] == 1:
        x = wp.clamp(x, 0, w - 1)
        y = wp.clamp(y, 0, h - 1)
    elif x < 0 or y < 0 or x >= w or y >= h:
        return wp.vec3(0.0)
    return T.pixels[img[0] + y * w + x]


@wp.func
def _bilinear(T: Textures, img: wp.vec4i, st: wp.vec2) -> wp.vec3:
    """Bilinear lookup; t is flipped as in pbrt-v4 so v = 0 is the image's bottom row."""
    x = st[0] * float(img[1]) - 0.5
    y = (1.0 - st[1]) * float(img[2]) - 0.5
    x0 = wp.floor(x)
    y0 = wp.floor(y)
    fx = x - x0
    fy = y - y0
    ix = int(x0)
    iy = int(y0)
    a = _texel(T, img, ix, iy) * (1.0 - fx) + _texel(T, img, ix + 1, iy) * fx
    b = _texel(T, img, ix, iy + 1) * (1.0 - fx) + _texel(T, img, ix + 1, iy + 1) * fx
    return a * (1.0 - fy) + b * fy


@wp.func
def _coordinates(T: Textures, tid: int, uv: wp.vec2, p: wp.vec3) -> wp.vec2:
    """pbrt-v4's TextureMapping2D: (s, t) from the surface's uv or its world-space point."""
    m = T.uvmap[tid]
    mapping = T.mapping[tid]
    if mapping == UV:
        return wp.vec2(uv[0] * m[0] + m[2], uv[1] * m[1] + m[3])
    q = wp.transform_point(T.xform[tid], p)
    if mapping == SPHERICAL:
        v = wp.normalize(q)
        phi = wp.atan2(v[1], v[0])
        if phi < 0.0:
            phi = phi + 2.0 * wp.pi
        return wp.vec2(wp.acos(wp.clamp(v[2], -1.0, 1.0)) / wp.pi, phi / (2.0 * wp.pi))
    if mapping == CYLINDRICAL:
        return wp.vec2((wp.pi + wp.atan2(q[1], q[0])) / (2.0 * wp.pi), q[2])
    return wp.vec2(q[0] + m[2], q[1] + m[3])


@wp.func
def texture_eval(T: Textures, tid: int, uv: wp.vec2, p: wp.vec3, n: wp.vec3) -> wp.vec3:
    """The texture's value at surface coordinates uv, world point p and geometric normal n (float
    textures use the first channel)."""
    k = T.kind[tid]
    if k < MIX:
        return _plain(T, tid, uv, p)
    c = T.inputs[tid]
    a = _plain(T, c[0], uv, p)
    b = _plain(T, c[1], uv, p)
    if k == PRODUCT:
        return wp.cw_mul(T.scale[tid], wp.cw_mul(a, b))
    if k == MIX:
        t = _plain(T, c[2], uv, p)[0]
        return wp.cw_mul(T.scale[tid], a * (1.0 - t) + b * t)
    t = wp.abs(wp.dot(n, T.alt[tid]))
    return wp.cw_mul(T.scale[tid], a * t + b * (1.0 - t))


@wp.func
def _plain(T: Textures, tid: int, uv: wp.vec2, p: wp.vec3) -> wp.vec3:
    """A constant, image or checkerboard record's value."""
    k = T.kind[tid]
    if k == CONSTANT:
        return T.scale[tid]
    st = _coordinates(T, tid, uv, p)
    if k == CHECKERBOARD:
        if (int(wp.floor(st[0])) + int(wp.floor(st[1]))) % 2 == 0:
            return T.scale[tid]
        return T.alt[tid]
    return wp.cw_mul(T.scale[tid], _bilinear(T, T.image[tid], st))


@dataclass
class TextureTable:
    """Host-side builder of the texture table; ``add_*`` return ids that materials store."""

    kind: list[int] = field(default_factory=list)
    scale: list[np.ndarray] = field(default_factory=list)
    alt: list[np.ndarray] = field(default_factory=list)
    uvmap: list[tuple[float, float, float, float]] = field(default_factory=list)
    mapping: list[int] = field(default_factory=list)
    inputs: list[tuple[int, int, int]] = field(default_factory=list)
    xform: list[tuple[float, ...]] = field(default_factory=list)
    image: list[tuple[int, int, int, int]] = field(default_factory=list)
    pixels: list[np.ndarray] = field(default_factory=list)
    n_pixels: int = 0
    named: dict[tuple[str, str], int] = field(default_factory=dict)
    _image_cache: dict[tuple[Path, str], tuple[int, int, int]] = field(default_factory=dict)

    def _add(self, kind: int, scale, alt=(0.0, 0.0, 0.0), uvmap=(1.0, 1.0, 0.0, 0.0), image=(0, 1, 1, 0),
             mapping: int = UV, xform: tuple[float, ...] = tuple(np.eye(4).ravel()),
             inputs: tuple[int, int, int] = (0, 0, 0)) -> int:
        self.kind.append(kind)
        self.inputs.append(tuple(int(i) for i in inputs))
        self.mapping.append(int(mapping))
        self.xform.append(tuple(float(x) for x in xform))
        self.scale.append(np.broadcast_to(np.asarray(scale, dtype=np.float32), (3,)))
        self.alt.append(np.broadcast_to(np.asarray(alt, dtype=np.float32), (3,)))
        self.uvmap.append(tuple(float(x) for x in uvmap))
        self.image.append(tuple(int(x) for x in image))
        return len(self.kind) - 1

    def add_constant(self, value) -> int:
        return self._add(CONSTANT, value)

    def _load_image(self, path: Path, encoding: str, loc, invert_scale: float | None = None) -> tuple[int, int, int]:
        """The image's place in the pool; with ``invert_scale`` s, its texels become
        max(0, 1 - s x texel), pbrt's imagemap "invert" (applied per texel, before interpolation)."""
        from renderer.io.images import read_image

        key = (path, encoding, invert_scale)
        if key not in self._image_cache:
            try:
                img = read_image(path, srgb=(encoding.lower() == "srgb"))
            except Exception as e:  # unreadable or corrupt image: say which file
                raise SceneError(f"cannot read texture image {path}: {e}", loc) from e
            if encoding.startswith("gamma "):
                img = np.power(np.clip(img, 0, None), float(encoding.split()[1]))
            rgb = np.repeat(img[..., :1], 3, axis=2) if img.shape[2] < 3 else img[..., :3]
            if not np.all(np.isfinite(rgb)):
                raise SceneError(f"texture image {path} contains NaN or infinite values", loc)
            if invert_scale is not None:
                rgb = np.maximum(0.0, 1.0 - invert_scale * rgb)
            h, w = rgb.shape[:2]
            self._image_cache[key] = (self._add_pixels(rgb.reshape(-1, 3)), w, h)
        return self._image_cache[key]

    def _add_pixels(self, rgb: np.ndarray) -> int:
        """Append (N, 3) texels to the pool; their offset."""
        self.pixels.append(np.ascontiguousarray(rgb, dtype=np.float32))
        self.n_pixels += len(rgb)
        return self.n_pixels - len(rgb)

    def add_described(self, desc: TextureDesc, textures: dict[str, TextureDesc]) -> int:
        """Add a named texture from the scene (memoised, so materials sharing it share one record)."""
        key = (desc.name, desc.value_type)
        if key in self.named:
            return self.named[key]
        spec = read_texture(desc)
        if spec.kind == "constant":
            tid = self.add_constant(spec.value)
        elif spec.kind == "imagemap":
            off, w, h = self._load_image(spec.path, spec.encoding, desc.loc, spec.value if spec.invert else None)
            tid = self._add(IMAGE, 1.0 if spec.invert else spec.value, uvmap=spec.uvmap,
                            image=(off, w, h, WRAP[spec.wrap]), **self._mapped(spec))
        elif spec.kind == "bilerp":                # a 2x2 image: rows t = 1 (v01, v11), t = 0 (v00, v10)
            v00, v01, v10, v11 = spec.corners
            off = self._add_pixels(np.stack([v01, v11, v00, v10]))
            tid = self._add(IMAGE, 1.0, uvmap=spec.uvmap, image=(off, 2, 2, WRAP["clamp"]), **self._mapped(spec))
        elif spec.kind == "checkerboard":
            tid = self._add(CHECKERBOARD, spec.value, alt=spec.alt, uvmap=spec.uvmap, **self._mapped(spec))
        elif spec.kind in ("mix", "directionmix", "product"):
            kind = {"mix": MIX, "directionmix": DIRECTION_MIX, "product": PRODUCT}[spec.kind]
            types = (desc.value_type, desc.value_type, "float")        # a mix's amount is a float texture
            ids = [self._input(v, t, desc, textures) for v, t in zip(spec.inputs, types)]
            tid = self._add(kind, spec.value, alt=spec.alt, inputs=(*ids, *[0] * (3 - len(ids))))
        elif spec.base is None:             # a scale of two constants
            tid = self.add_constant(spec.value)
        else:
            tid = self._scaled(self.lookup(spec.base, desc.value_type, textures, desc.loc), spec.value)
        self.named[key] = tid
        return tid

    def _input(self, v, value_type: str, desc: TextureDesc, textures: dict[str, TextureDesc]) -> int:
        """An input of a mix or product: a constant, or a named texture that is not itself one."""
        if not isinstance(v, str):
            return self.add_constant(v)
        tid = self.lookup(v, value_type, textures, desc.loc)
        if self.kind[tid] >= MIX:
            raise SceneError(f'Texture "{desc.name}": its input "{v}" is itself a mix, directionmix or scale of '
                             "two textures; one level of these is supported", desc.loc)
        return tid

    @staticmethod
    def _mapped(spec) -> dict:
        return {"mapping": MAPPINGS[spec.mapping], "xform": spec.xform}

    def _scaled(self, base: int, factor: np.ndarray) -> int:
        """A copy of record ``base`` with its values multiplied by ``factor`` (pbrt's scale texture)."""
        self.kind.append(self.kind[base])
        self.scale.append(self.scale[base] * factor)
        self.alt.append(self.alt[base] if self.kind[base] == DIRECTION_MIX else self.alt[base] * factor)
        self.uvmap.append(self.uvmap[base])
        self.inputs.append(self.inputs[base])
        self.mapping.append(self.mapping[base])
        self.xform.append(self.xform[base])
        self.image.append(self.image[base])
        return len(self.kind) - 1

    def lookup(self, name: str, value_type: str, textures: dict[str, TextureDesc], loc) -> int:
        desc = find_texture(textures, name, value_type)
        if desc is None:
            raise SceneError(f'unknown texture "{name}"', loc)
        return self.add_described(desc, textures)

    def upload(self, device: str) -> tuple[Textures, list]:
        T = Textures()
        n = max(1, len(self.kind))
        pad = lambda a, shape: np.asarray(a, dtype=np.float32).reshape(shape) if len(a) else np.zeros(shape, np.float32)
        T.kind = wp.array(np.asarray(self.kind or [0], dtype=np.int32), dtype=int, device=device)
        T.scale = wp.array(pad(self.scale, (n, 3)), dtype=wp.vec3, device=device)
        T.alt = wp.array(pad(self.alt, (n, 3)), dtype=wp.vec3, device=device)
        T.uvmap = wp.array(pad(self.uvmap, (n, 4)), dtype=wp.vec4, device=device)
        T.inputs = wp.array(np.asarray(self.inputs or [(0, 0, 0)], dtype=np.int32), dtype=wp.vec3i, device=device)
        T.mapping = wp.array(np.asarray(self.mapping or [UV], dtype=np.int32), dtype=int, device=device)
        T.xform = wp.array(pad(self.xform, (n, 4, 4)), dtype=wp.mat44, device=device)
        T.image = wp.array(np.asarray(self.image or [(0, 1, 1, 0)], dtype=np.int32), dtype=wp.vec4i, device=device)
        pix = np.concatenate(self.pixels) if self.pixels else np.zeros((1, 3), np.float32)
        T.pixels = wp.array(pix, dtype=wp.vec3, device=device)
        return T, [T.kind, T.scale, T.alt, T.inputs, T.uvmap, T.mapping, T.xform, T.image, T.pixels]
