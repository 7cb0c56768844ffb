"""A texture's pbrt parameters read and checked once, without Warp: the builder calls
:func:`read_texture` at load time so a bad class, value or missing image is reported with its
file:line before any device work, and the device texture table builds from the same record."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from renderer.errors import Location, SceneError, UnsupportedError
from renderer.scene.description import TextureDesc, find_texture
from renderer.scene.parser import require_file
from renderer.scene.support import SUPPORTED_TEXTURES, TEXTURE_CLASSES

#: imagemap "wrap" modes, numbered as the device's texel lookup reads them
WRAP = {"repeat": 0, "clamp": 1, "black": 2}
#: pbrt-v4's 2D texture mappings, numbered as the device reads them
MAPPINGS = {"uv": 0, "spherical": 1, "cylindrical": 2, "planar": 3}
#: values the device's postfix evaluation of a combined texture may hold at once
STACK_DEPTH = 8

Value = float | np.ndarray        # a float texture's scalar or a spectrum texture's RGB


@dataclass(frozen=True)
class TextureSpec:
    """What a texture's parameters say, as plain values (one record per ``Texture`` directive)."""

    kind: str                                        # one of SUPPORTED_TEXTURES
    value: Value                                     # constant; imagemap scale; checkerboard tex1; scale factor
    alt: Value = 0.0                                 # checkerboard tex2
    uvmap: tuple[float, float, float, float] = (1.0, 1.0, 0.0, 0.0)   # (su, sv, du, dv)
    path: Path | None = None                         # imagemap file
    encoding: str = "sRGB"                           # imagemap encoding: sRGB, linear or "gamma G"
    wrap: str = "repeat"                             # imagemap wrap mode (a key of WRAP)
    base: str | None = None                          # scale: the one factor that is a texture
    mapping: str = "uv"                              # a key of MAPPINGS
    #: texture-from-world (4, 4) for the spherical/cylindrical mappings; for planar its first two
    #: rows are pbrt's v1 and v2 applied after that transform (s, t = row . (p, 1) + udelta, vdelta)
    xform: tuple[float, ...] = tuple(np.eye(4).ravel())
    invert: bool = False                             # imagemap: 1 - value, clamped at 0
    corners: tuple | None = None                     # bilerp: v00, v01, v10, v11
    #: mix: (tex1, tex2, amount); directionmix: (tex1, tex2); product (a scale of two textures):
    #: (tex, scale); select: (first, second). Each a texture's name or a constant.
    inputs: tuple = ()
    #: select: which pattern picks the second input ("checker2d", "checker3d" or "dots")
    pattern: str = ""
    #: fbm, wrinkled, marble: (octaves, roughness, scale, variation)
    noise: tuple[float, float, float, float] = (8.0, 0.5, 1.0, 0.2)

    @property
    def refs(self) -> list[str]:
        """The textures this one reads, which must be defined before it (as in pbrt-v4)."""
        return [r for r in (self.base, *self.inputs) if isinstance(r, str)]


def read_texture(desc: TextureDesc) -> TextureSpec:
    """Check the class and read every parameter it uses; leftovers stay unread in ``desc.params``
    for the builder's unused-parameter warning."""
    where = f'Texture "{desc.name}"'
    if desc.kind not in TEXTURE_CLASSES:
        raise UnsupportedError(f'{where}: unknown texture class "{desc.kind}" (pbrt-v4 knows '
                               f'{", ".join(sorted(TEXTURE_CLASSES))})', desc.loc)
    if desc.kind not in SUPPORTED_TEXTURES:
        raise UnsupportedError(f'{where}: class "{desc.kind}" is not supported (supported: '
                               f'{", ".join(sorted(SUPPORTED_TEXTURES))})', desc.loc)
    p = desc.params
    const = p.float if desc.value_type == "float" else p.rgb
    if desc.kind == "constant":
        return TextureSpec("constant", const("value", 1.0))
    if desc.kind == "scale":
        return _scale(desc, where)
    if desc.kind in ("mix", "directionmix"):
        return _mix(desc)
    if desc.kind in NOISE_TEXTURES:
        return _noise(desc, where)
    if desc.kind == "checkerboard" and p.int("dimension", 2) != 2:
        return _checkerboard_3d(desc, where)
    mapped = _mapping(desc, where)
    if desc.kind == "bilerp":
        return _bilerp(desc, where, mapped, const)
    read = p.float_or_texture if desc.value_type == "float" else p.rgb_or_texture
    if desc.kind == "dots":
        # pbrt-v4 hands "inside" to its DotsTexture's outsideDot and "outside" to insideDot, so
        # its dots show "outside" (default 0) and the space between them "inside" (default 1)
        return replace(mapped, kind="select", value=1.0, pattern="dots", inputs=(read("inside", 1.0),
                                                                                read("outside", 0.0)))
    if desc.kind == "checkerboard":
        tex1, tex2 = read("tex1", 1.0), read("tex2", 0.0)
        if isinstance(tex1, str) or isinstance(tex2, str):
            return replace(mapped, kind="select", value=1.0, pattern="checker2d", inputs=(tex1, tex2))
        return replace(mapped, kind="checkerboard", value=tex1, alt=tex2)
    return _imagemap(desc, where, mapped)


#: pbrt-v4's noise textures, and the value type each exists for
NOISE_TEXTURES = {"fbm": "float", "wrinkled": "float", "windy": "float", "marble": "spectrum"}


def _texture_from_world(desc: TextureDesc) -> tuple[float, ...]:
    """pbrt-v4's TextureMapping3D: the point in texture space (the CTM at the Texture directive)."""
    return tuple(float(x) for x in np.linalg.inv(desc.ctm if desc.ctm is not None else np.eye(4)).ravel())


def _noise(desc: TextureDesc, where: str) -> TextureSpec:
    """fbm and wrinkled (octaves, roughness), windy, marble (also scale, variation), with pbrt-v4's
    defaults, of the texture-space point."""
    if desc.value_type != NOISE_TEXTURES[desc.kind]:
        raise SceneError(f'{where}: pbrt-v4 has "{desc.kind}" as a {NOISE_TEXTURES[desc.kind]} texture only',
                         desc.loc)
    p = desc.params
    noise = (8.0, 0.5, 1.0, 0.2)
    if desc.kind != "windy":
        noise = (float(p.int("octaves", 8, min=0)), p.float("roughness", 0.5), 1.0, 0.2)
    if desc.kind == "marble":
        noise = (*noise[:2], p.float("scale", 1.0), p.float("variation", 0.2))
    return TextureSpec(desc.kind, 1.0, xform=_texture_from_world(desc), noise=noise)


def _checkerboard_3d(desc: TextureDesc, where: str) -> TextureSpec:
    """pbrt-v4's 3D checkerboard: tex1 where floor(x) + floor(y) + floor(z) of the texture-space
    point is even, tex2 where it is odd."""
    p = desc.params
    if p.int("dimension", 2) != 3:
        raise SceneError(f'{where}: checkerboard "dimension" must be 2 or 3', p.params["dimension"].loc)
    read = p.float_or_texture if desc.value_type == "float" else p.rgb_or_texture
    return TextureSpec("select", 1.0, xform=_texture_from_world(desc), pattern="checker3d",
                       inputs=(read("tex1", 1.0), read("tex2", 0.0)))


def _mapping(desc: TextureDesc, where: str) -> TextureSpec:
    """pbrt-v4's TextureMapping2D: "uv" (uscale, vscale, udelta, vdelta), "spherical" and
    "cylindrical" about the texture space's origin and z axis, "planar" (v1, v2, udelta, vdelta);
    texture space is the CTM at the Texture directive."""
    p = desc.params
    mapping = p.string("mapping", "uv")
    if mapping not in MAPPINGS:
        raise SceneError(f'{where}: unknown mapping "{mapping}" (pbrt-v4 knows {", ".join(MAPPINGS)})',
                         p.params["mapping"].loc)
    if mapping == "uv":
        uvmap = (p.float("uscale", 1.0), p.float("vscale", 1.0), p.float("udelta", 0.0), p.float("vdelta", 0.0))
        return TextureSpec("", 0.0, uvmap=uvmap)
    m = np.linalg.inv(desc.ctm if desc.ctm is not None else np.eye(4))
    uvmap = (1.0, 1.0, 0.0, 0.0)
    if mapping == "planar":
        v1, v2 = (_vector(p, name, default, where) for name, default in (("v1", (1, 0, 0)), ("v2", (0, 1, 0))))
        rows = np.zeros((4, 4))
        rows[0], rows[1], rows[3, 3] = v1 @ m[:3], v2 @ m[:3], 1.0
        m, uvmap = rows, (1.0, 1.0, p.float("udelta", 0.0), p.float("vdelta", 0.0))
    return TextureSpec("", 0.0, uvmap=uvmap, mapping=mapping, xform=tuple(float(x) for x in m.ravel()))


def _vector(p, name: str, default: tuple, where: str) -> np.ndarray:
    v = p.floats(name, ("vector3", "vector", "normal3", "point3", "float"))
    if v is None:
        return np.asarray(default, dtype=np.float64)
    if len(v) != 3:
        raise SceneError(f'{where}: "{name}" needs 3 values, got {len(v)}', p.params[name].loc)
    return v


def _imagemap(desc: TextureDesc, where: str, mapped: TextureSpec) -> TextureSpec:
    p = desc.params
    fname = p.string("filename")
    if not fname:
        raise SceneError(f'{where}: imagemap needs "string filename"', desc.loc)
    path = (desc.base_dir / fname).resolve()
    require_file(path, desc.loc, "texture image")
    encoding = p.string("encoding", "linear" if path.suffix.lower() in (".exr", ".hdr", ".pfm") else "sRGB")
    check_encoding(encoding, where, desc.loc)
    wrap = p.string("wrap", "repeat")
    if wrap not in WRAP:
        raise SceneError(f'{where}: imagemap wrap must be one of {sorted(WRAP)}, got "{wrap}"', desc.loc)
    scale = p.float("scale", 1.0)
    p.string("filter")                     # the filter is always bilinear; asking for another is fine
    return replace(mapped, kind="imagemap", value=scale, path=path, encoding=encoding, wrap=wrap,
                   invert=bool(p.bool("invert", False)))


def check_encoding(encoding: str, where: str, loc: Location) -> None:
    """pbrt-v4's image encodings: "sRGB", "linear" or "gamma G" with G a positive finite number."""
    words = encoding.split(" ")
    if encoding.lower() in ("srgb", "linear"):
        return
    if len(words) == 2 and words[0] == "gamma":
        try:
            g = float(words[1])
        except ValueError:
            g = float("nan")
        if math.isfinite(g) and g > 0.0:
            return
    raise SceneError(f'{where}: encoding must be "sRGB", "linear" or "gamma G" with G > 0, got "{encoding}"', loc)


def program_depth(spec: TextureSpec, textures: dict[str, TextureDesc], value_type: str) -> int:
    """How many values the device's postfix evaluation of this texture holds at once (a leaf: 1)."""
    if spec.base is not None:
        base = find_texture(textures, spec.base, value_type)
        return program_depth(read_texture(base), textures, value_type) if base is not None else 1
    types = (value_type, value_type, "float") if spec.kind == "mix" else (value_type,) * 2
    depth = 1
    for i, (r, t) in enumerate(zip(spec.inputs, types)):
        sub = find_texture(textures, r, t) if isinstance(r, str) else None
        depth = max(depth, i + (program_depth(read_texture(sub), textures, t) if sub is not None else 1))
    return depth


def check_depth(spec: TextureSpec, desc: TextureDesc, textures: dict[str, TextureDesc]) -> None:
    """Textures combine textures to any depth, but the device evaluates them with a stack of
    STACK_DEPTH values: refused at load beyond it."""
    if program_depth(spec, textures, desc.value_type) > STACK_DEPTH:
        raise UnsupportedError(f'Texture "{desc.name}": its inputs nest too deeply (the device evaluates '
                               f"combined textures with a stack of {STACK_DEPTH} values)", desc.loc)


def _bilerp(desc: TextureDesc, where: str, mapped: TextureSpec, const) -> TextureSpec:
    """pbrt's bilerp, (1-s)(1-t) v00 + (1-s) t v01 + s (1-t) v10 + s t v11, made a 2x2 image whose
    texel centres sit at s, t = 0 and 1 (the mapping is narrowed to them): the device's bilinear
    lookup is then the same function on [0, 1]^2. Outside it the image clamps where pbrt's formula
    extrapolates. Spherical and cylindrical coordinates lie in [0, 1] anyway but cannot be
    narrowed here, so they are refused."""
    if mapped.mapping in ("spherical", "cylindrical"):
        raise UnsupportedError(f'{where}: bilerp with the "{mapped.mapping}" mapping is not supported', desc.loc)
    corners = tuple(np.broadcast_to(np.asarray(const(k, 0.0), dtype=np.float64), (3,))
                    for k in ("v00", "v01", "v10", "v11"))
    su, sv, du, dv = mapped.uvmap
    uvmap = (0.5 * su, 0.5 * sv, 0.25 + 0.5 * du, 0.25 + 0.5 * dv)
    xform = mapped.xform
    if mapped.mapping == "planar":                         # st = rows . p + delta: narrow the rows too
        m = np.asarray(xform).reshape(4, 4).copy()
        m[:2] *= 0.5
        xform = tuple(float(x) for x in m.ravel())
    return replace(mapped, kind="bilerp", value=1.0, uvmap=uvmap, xform=xform, corners=corners, wrap="clamp")


def _mix(desc: TextureDesc) -> TextureSpec:
    """pbrt-v4's mix, (1 - amount) tex1 + amount tex2, and directionmix, a tex1 + (1 - a) tex2
    with a = |n . dir| (dir given in texture space, normalised in world space)."""
    p = desc.params
    read = p.float_or_texture if desc.value_type == "float" else p.rgb_or_texture
    tex1, tex2 = read("tex1", 0.0), read("tex2", 1.0)
    if desc.kind == "mix":
        return TextureSpec("mix", 1.0, inputs=(tex1, tex2, p.float_or_texture("amount", 0.5)))
    d = _vector(p, "dir", (0.0, 1.0, 0.0), f'Texture "{desc.name}"')
    world = (desc.ctm if desc.ctm is not None else np.eye(4))[:3, :3] @ d
    if not np.linalg.norm(world) > 0.0:
        raise SceneError(f'Texture "{desc.name}": "dir" must not be zero', desc.loc)
    return TextureSpec("directionmix", 1.0, alt=world / np.linalg.norm(world), inputs=(tex1, tex2))


def _scale(desc: TextureDesc, where: str) -> TextureSpec:
    """pbrt's ``scale`` texture (tex × scale): a constant factor folds into the other factor's
    multiplier; two textures make a product record."""
    p = desc.params
    read = p.float_or_texture if desc.value_type == "float" else p.rgb_or_texture
    tex, scale = read("tex", 1.0), read("scale", 1.0)
    if isinstance(tex, str) and isinstance(scale, str):
        return TextureSpec("product", 1.0, inputs=(tex, scale))
    if isinstance(tex, str) or isinstance(scale, str):
        base, factor = (tex, scale) if isinstance(tex, str) else (scale, tex)
        return TextureSpec("scale", np.asarray(factor, dtype=np.float32), base=base)
    return TextureSpec("scale", np.asarray(tex) * np.asarray(scale))
