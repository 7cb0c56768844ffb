"""The host side of the texture table: scene textures become device records (see
:mod:`renderer.textures.evaluate`), memoised by name, with every combination's postfix program
built at upload."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import warp as wp

from renderer.device.pools import pooled
from renderer.errors import SceneError
from renderer.scene.description import TextureDesc, find_texture
from renderer.scene.texture_params import MAPPINGS, WRAP, read_texture
from renderer.textures.evaluate import (ARITY, ONE_FLOAT, RGB_FLOAT, CHECKER_2D, CHECKER_3D, CHECKERBOARD, CONSTANT, DIRECTION_MIX, DOTS,
                                        FBM, IMAGE, MARBLE, MIX, PRODUCT, SELECT, UV, WINDY, WRINKLED,
                                        Textures)
from renderer.textures.noise import permutation

NOISE = {"fbm": FBM, "wrinkled": WRINKLED, "windy": WINDY, "marble": MARBLE}
COMBINED = {"mix": MIX, "directionmix": DIRECTION_MIX, "product": PRODUCT, "select": SELECT}
PATTERNS = {"checker2d": CHECKER_2D, "checker3d": CHECKER_3D, "dots": DOTS}

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
    proc: list[tuple[float, float, float, float]] = field(default_factory=list)
    store: list[tuple[int, int]] = field(default_factory=list)    # how each record's texels are held (evaluate.py)
    pixels: list[np.ndarray] = field(default_factory=list)        # float texels, (N, 3) float32 each
    n_pixels: int = 0
    codes: list[np.ndarray] = field(default_factory=list)         # 8-bit texels, flat uint8 each
    n_codes: int = 0
    values: list[np.ndarray] = field(default_factory=list)        # 8-bit images' code tables, 1-channel float images
    n_values: int = 0
    named: dict[tuple[str, str], int] = field(default_factory=dict)
    _image_cache: dict[tuple, tuple[int, int, int, tuple[int, int]]] = field(default_factory=dict)

    def _add(self, kind: int, scale, alt=(0.0, 0.0, 0.0), uvmap=(1.0, 1.0, 0.0, 0.0), image=(0, 1, 1, 0),
             mapping: int = UV, xform: tuple[float, ...] = tuple(np.eye(4).ravel()),
             inputs: tuple[int, int, int] = (0, 0, 0), proc: tuple[float, ...] = (0.0,) * 4,
             store: tuple[int, int] = (0, 0)) -> int:
        self.kind.append(kind)
        self.store.append(store)
        self.proc.append(tuple(float(x) for x in proc))
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

    def _load_image(self, path: Path, encoding: str, loc,
                    invert_scale: float | None = None) -> tuple[int, int, int, tuple[int, int]]:
        """The image's place: (offset, width, height, store), memoised. An 8-bit file stays 8-bit,
        one or three channels as the file has them, with a 256-entry table of what each code
        means; every per-texel step (sRGB or gamma decode, ``invert_scale`` s: pbrt's imagemap
        "invert", max(0, 1 - s x texel)) is applied to that table, so a texel reads exactly the
        value a float pool would hold. Other files become float32 texels, one channel or three.
        Every store reads a texel as the same three floats, so renders do not depend on it."""
        from renderer.io.images import code_values, linear, read_stored

        key = (path, encoding, invert_scale)
        if key in self._image_cache:
            return self._image_cache[key]
        srgb = encoding.lower() == "srgb"
        try:
            stored = read_stored(path, max_channels=3)
        except Exception as e:  # unreadable or corrupt image: say which file
            raise SceneError(f"cannot read texture image {path}: {e}", loc) from e
        h, w, c = stored.shape
        eight_bit = stored.dtype == np.uint8
        values = code_values(srgb) if eight_bit else linear(stored, srgb)
        if encoding.startswith("gamma "):
            values = np.power(np.clip(values, 0, None), float(encoding.split()[1]))
        if not eight_bit and c == 2:                   # grey + alpha: the grey
            values = values[..., :1]
        if not np.all(np.isfinite(values)):
            raise SceneError(f"texture image {path} contains NaN or infinite values", loc)
        if invert_scale is not None:
            values = np.maximum(0.0, 1.0 - invert_scale * values)
        if eight_bit:
            channels = 1 if c < 3 else 3
            codes = stored[..., 0] if channels < c else stored     # a grey+alpha file keeps its grey
            place = (self._add_codes(codes.ravel()), w, h, (channels, self._add_values(values)))
        elif values.shape[2] == 1:
            place = (self._add_values(values.ravel()), w, h, (ONE_FLOAT, 0))
        else:
            place = (self._add_pixels(values.reshape(-1, 3)), w, h, (RGB_FLOAT, 0))
        self._image_cache[key] = place
        return place

    def _add_pixels(self, rgb: np.ndarray) -> int:
        """Append (N, 3) float texels to the pool; their offset."""
        self.pixels.append(np.ascontiguousarray(rgb, dtype=np.float32))
        self.n_pixels += len(rgb)
        return self.n_pixels - len(rgb)

    def _add_codes(self, codes: np.ndarray) -> int:
        """Append 8-bit texels (flat, channels interleaved) to the code pool; their offset. Device
        code indexes the pool with 32-bit integers, so it holds at most 2^31 - 1 bytes."""
        if self.n_codes + codes.size >= 2**31:
            raise SceneError(f"8-bit texture images total more than 2^31 bytes ({self.n_codes + codes.size}); "
                             "use smaller images", None)
        self.codes.append(np.ascontiguousarray(codes, dtype=np.uint8))
        self.n_codes += codes.size
        return self.n_codes - codes.size

    def _add_values(self, values: np.ndarray) -> int:
        """Append floats (an 8-bit image's 256 code values, or a one-channel image's texels) to
        the value pool; their offset (32-bit on the device, as for the code pool)."""
        if self.n_values + values.size >= 2**31:
            raise SceneError(f"one-channel texture images total more than 2^31 texels ({self.n_values + values.size}); "
                             "use smaller images", None)
        self.values.append(np.ascontiguousarray(values, dtype=np.float32).ravel())
        self.n_values += values.size
        return self.n_values - values.size

    def add_described(self, desc: TextureDesc, textures: dict[str, TextureDesc]) -> int:
        """Add a named texture from the scene (memoised, so materials sharing it share one record)."""
        key = (desc.name, desc.value_type)
        if key in self.named:
            return self.named[key]
        spec = read_texture(desc)
        if spec.kind == "constant":
            tid = self.add_constant(spec.value)
        elif spec.kind == "imagemap":
            off, w, h, store = self._load_image(spec.path, spec.encoding, desc.loc,
                                                spec.value if spec.invert else None)
            tid = self._add(IMAGE, 1.0 if spec.invert else spec.value, uvmap=spec.uvmap,
                            image=(off, w, h, WRAP[spec.wrap]), store=store, **self._mapped(spec))
        elif spec.kind == "bilerp":                # a 2x2 image: rows t = 1 (v01, v11), t = 0 (v00, v10)
            v00, v01, v10, v11 = spec.corners
            off = self._add_pixels(np.stack([v01, v11, v00, v10]))
            tid = self._add(IMAGE, 1.0, uvmap=spec.uvmap, image=(off, 2, 2, WRAP["clamp"]), **self._mapped(spec))
        elif spec.kind == "checkerboard":
            tid = self._add(CHECKERBOARD, spec.value, alt=spec.alt, uvmap=spec.uvmap, **self._mapped(spec))
        elif spec.kind in NOISE:
            tid = self._add(NOISE[spec.kind], spec.value, xform=spec.xform, proc=spec.noise)
        elif spec.kind in COMBINED:
            types = (desc.value_type, desc.value_type, "float")        # a mix's amount is a float texture
            ids = [self._input(v, t, desc, textures) for v, t in zip(spec.inputs, types)]
            tid = self._add(COMBINED[spec.kind], spec.value, alt=spec.alt, inputs=(*ids, *[0] * (3 - len(ids))),
                            uvmap=spec.uvmap, proc=(PATTERNS.get(spec.pattern, 0), 0, 0, 0), **self._mapped(spec))
        elif spec.base is None:             # a scale of two constants
            tid = self.add_constant(spec.value)
        else:
            tid = self._scaled(self.lookup(spec.base, desc.value_type, textures, desc.loc), spec.value)
        self.named[key] = tid
        return tid

    def _input(self, v, value_type: str, desc: TextureDesc, textures: dict[str, TextureDesc]) -> int:
        """An input of a combination: a constant, or a named texture (itself combined or not)."""
        if not isinstance(v, str):
            return self.add_constant(v)
        return self.lookup(v, value_type, textures, desc.loc)

    def _program(self, tid: int) -> list[int]:
        """The record ids that evaluate ``tid`` in postfix order: its inputs' programs, then itself."""
        if self.kind[tid] < MIX:
            return [tid]
        return [i for c in self.inputs[tid][:ARITY[self.kind[tid]]] for i in self._program(c)] + [tid]

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
        self.store.append(self.store[base])
        self.proc.append(self.proc[base])
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
        T.proc = wp.array(pad(self.proc, (n, 4)), dtype=wp.vec4, device=device)
        programs = [self._program(t) if k >= MIX else [] for t, k in enumerate(self.kind)]
        starts = np.cumsum([0] + [len(q) for q in programs])[:-1]
        prog = [(int(a), len(q)) for a, q in zip(starts, programs)] or [(0, 0)]
        T.prog = wp.array(np.asarray(prog, dtype=np.int32), dtype=wp.vec2i, device=device)
        T.program = wp.array(np.asarray([i for q in programs for i in q] or [0], dtype=np.int32), dtype=int,
                             device=device)
        T.store = wp.array(np.asarray(self.store or [(0, 0)], dtype=np.int32), dtype=wp.vec2i, device=device)
        T.pixels = pooled(self.pixels, np.zeros((1, 3), np.float32), wp.vec3, device)
        T.codes = pooled(self.codes, np.zeros(1, np.uint8), wp.uint8, device)
        T.values = pooled(self.values, np.zeros(1, np.float32), float, device)
        T.perm = wp.array(permutation(), dtype=int, device=device)
        return T, [T.kind, T.scale, T.alt, T.inputs, T.uvmap, T.mapping, T.xform, T.image, T.store, T.proc, T.prog,
                   T.program, T.pixels, T.codes, T.values, T.perm]

