"""Texture evaluation on the device: one table of records and pools of image texels (float RGB,
one float channel, and 8-bit codes read through a 256-entry table per image, so an 8-bit or
one-channel file is not widened to float RGB). Every
material parameter is a texture id, so constants and maps share one path.

A record is either a leaf (constant, image, 2D checkerboard of constants, fbm, wrinkled, windy,
marble), evaluated on its own, or a combination of other records (mix, directionmix, a scale of two
textures, and SELECT: a checkerboard (2D or 3D) or dots choosing between two textures). Warp
functions cannot recurse, so a combination is evaluated as a postfix program over its tree (built
at upload): leaves push their values onto a small stack, combinations pop their inputs and push
the result. Leaves map the hit with pbrt-v4's 2D mappings (the surface's uv, or
spherical/cylindrical/planar of the texture-space point) or its 3D mapping (the texture-space point,
pbrt's PointTransformMapping)."""
from __future__ import annotations

import warp as wp

from renderer.scene.texture_params import MAPPINGS, STACK_DEPTH
from renderer.textures.noise import fbm, inside_polka_dot, marble, turbulence, windy

CONSTANT, IMAGE, CHECKERBOARD, FBM, WRINKLED, WINDY, MARBLE = range(7)        # leaves
MIX, DIRECTION_MIX, PRODUCT, SELECT = range(7, 11)                            # combinations
#: how many values each combination pops (its inputs, in postfix order)
ARITY = {MIX: 3, DIRECTION_MIX: 2, PRODUCT: 2, SELECT: 2}
#: what a SELECT record's pattern is: a 2D or 3D checkerboard, or pbrt's dots
CHECKER_2D, CHECKER_3D, DOTS = range(3)
UV, SPHERICAL, CYLINDRICAL, PLANAR = (MAPPINGS[k] for k in ("uv", "spherical", "cylindrical", "planar"))
#: How an image record's texels are held (its ``store[0]``): float RGB in ``pixels``, one float
#: channel in ``values``, or 8-bit codes (1 or 3 channels) in ``codes`` read through 256 values
RGB_FLOAT, ONE_FLOAT = 0, -1
Stack = wp.types.matrix(shape=(STACK_DEPTH, 3), dtype=float)


@wp.struct
class Textures:
    kind: wp.array(dtype=int)
    scale: wp.array(dtype=wp.vec3)      # constant value, or multiplier of any other record's value
    alt: wp.array(dtype=wp.vec3)        # checkerboard tex2; directionmix: the world direction
    inputs: wp.array(dtype=wp.vec3i)    # mix (tex1, tex2, amount), directionmix/select (tex1, tex2), product (a, b)
    uvmap: wp.array(dtype=wp.vec4)      # (su, sv, du, dv): st = (su u + du, sv v + dv)
    mapping: wp.array(dtype=int)        # UV, SPHERICAL, CYLINDRICAL or PLANAR (3D records: the xform alone)
    xform: wp.array(dtype=wp.mat44)     # texture-from-world (planar: rows v1, v2 folded in)
    image: wp.array(dtype=wp.vec4i)     # (pixel offset, width, height, wrap mode)
    store: wp.array(dtype=wp.vec2i)     # (RGB_FLOAT, ONE_FLOAT or 1/3: 8-bit channels; code table offset)
    proc: wp.array(dtype=wp.vec4)       # noise (octaves, roughness, scale, variation); select: (pattern, ...)
    prog: wp.array(dtype=wp.vec2i)      # a combination's program: (first entry in program, length)
    program: wp.array(dtype=int)        # record ids in postfix order
    pixels: wp.array(dtype=wp.vec3)
    codes: wp.array(dtype=wp.uint8)     # 8-bit images as stored, channels interleaved
    values: wp.array(dtype=float)       # one-channel float images; 256 per 8-bit image: what each code means
    perm: wp.array(dtype=int)           # pbrt-v4's noise permutation table


@wp.func
def _texel(T: Textures, img: wp.vec4i, store: wp.vec2i, x: int, y: int) -> wp.vec3:
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
    i = y * w + x
    if store[0] == RGB_FLOAT:
        return T.pixels[img[0] + i]
    if store[0] == ONE_FLOAT:
        return wp.vec3(T.values[img[0] + i])
    if store[0] == 1:
        return wp.vec3(T.values[store[1] + int(T.codes[img[0] + i])])
    j = img[0] + 3 * i
    return wp.vec3(T.values[store[1] + int(T.codes[j])], T.values[store[1] + int(T.codes[j + 1])],
                   T.values[store[1] + int(T.codes[j + 2])])


@wp.func
def _bilinear(T: Textures, img: wp.vec4i, store: wp.vec2i, st: wp.vec2) -> wp.vec3:
    """Bilinear lookup; t is flipped as in pbrt-v4 so v = 0 is the image's bottom row."""
    x = st[0] * float(img[1]) - 0.5
    y = (1.0 - st[1]) * float(img[2]) - 0.5
    x0 = wp.floor(x)
    y0 = wp.floor(y)
    fx = x - x0
    fy = y - y0
    ix = int(x0)
    iy = int(y0)
    a = _texel(T, img, store, ix, iy) * (1.0 - fx) + _texel(T, img, store, ix + 1, iy) * fx
    b = _texel(T, img, store, ix, iy + 1) * (1.0 - fx) + _texel(T, img, store, ix + 1, iy + 1) * fx
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
def _noise_leaf(T: Textures, tid: int, k: int, p: wp.vec3) -> wp.vec3:
    """fbm, wrinkled, windy (float) or marble (spectrum) at the texture-space point."""
    q = wp.transform_point(T.xform[tid], p)
    c = T.proc[tid]
    octaves = int(c[0])
    if k == MARBLE:
        return wp.cw_mul(T.scale[tid], marble(T.perm, q, c[1], octaves, c[2], c[3]))
    v = float(0.0)
    if k == FBM:
        v = fbm(T.perm, q, c[1], octaves)
    elif k == WRINKLED:
        v = turbulence(T.perm, q, c[1], octaves)
    else:
        v = windy(T.perm, q)
    return T.scale[tid] * v


@wp.func
def _plain(T: Textures, tid: int, uv: wp.vec2, p: wp.vec3) -> wp.vec3:
    """A leaf record's value."""
    k = T.kind[tid]
    if k == CONSTANT:
        return T.scale[tid]
    if k >= FBM:
        return _noise_leaf(T, tid, k, p)
    st = _coordinates(T, tid, uv, p)
    if k == CHECKERBOARD:
        if (int(wp.floor(st[0])) + int(wp.floor(st[1]))) % 2 == 0:
            return T.scale[tid]
        return T.alt[tid]
    return wp.cw_mul(T.scale[tid], _bilinear(T, T.image[tid], T.store[tid], st))


@wp.func
def _selects_second(T: Textures, tid: int, uv: wp.vec2, p: wp.vec3) -> bool:
    """A SELECT record's choice: the odd squares or cubes of a checkerboard, or pbrt's dots (whose
    inputs pbrt-v4 swaps: its "inside" texture shows between the dots, see texture_params)."""
    pattern = int(T.proc[tid][0])
    if pattern == CHECKER_3D:
        q = wp.transform_point(T.xform[tid], p)
        return (int(wp.floor(q[0])) + int(wp.floor(q[1])) + int(wp.floor(q[2]))) % 2 != 0
    st = _coordinates(T, tid, uv, p)
    if pattern == DOTS:
        return inside_polka_dot(T.perm, st)
    return (int(wp.floor(st[0])) + int(wp.floor(st[1]))) % 2 != 0


@wp.func
def _combine(T: Textures, tid: int, k: int, a: wp.vec3, b: wp.vec3, c: wp.vec3, uv: wp.vec2, p: wp.vec3,
             n: wp.vec3) -> wp.vec3:
    """A combination record's value from its inputs ``a``, ``b`` (and a mix's amount ``c``), the
    top values of the stack in input order. Takes the rows, not the stack: a stack passed by value
    was a second copy of it in local memory (96 B of the frame)."""
    if k == MIX:
        t = c[0]
        return wp.cw_mul(T.scale[tid], a * (1.0 - t) + b * t)
    if k == PRODUCT:
        return wp.cw_mul(T.scale[tid], wp.cw_mul(a, b))
    if k == SELECT:
        if _selects_second(T, tid, uv, p):
            return wp.cw_mul(T.scale[tid], b)
        return wp.cw_mul(T.scale[tid], a)
    t = wp.abs(wp.dot(n, T.alt[tid]))
    return wp.cw_mul(T.scale[tid], a * t + b * (1.0 - t))


@wp.func(inline=True)
def texture_eval(T: Textures, tid: int, uv: wp.vec2, p: wp.vec3, n: wp.vec3) -> wp.vec3:
    """The texture's value at surface coordinates uv, world point p and geometric normal n (float
    textures use the first channel)."""
    if T.kind[tid] < MIX:
        return _plain(T, tid, uv, p)
    prog = T.prog[tid]
    s = Stack()
    top = int(0)
    for i in range(prog[1]):
        node = T.program[prog[0] + i]
        k = T.kind[node]
        v = wp.vec3(0.0)
        if k < MIX:
            v = _plain(T, node, uv, p)
        else:
            first = top - wp.where(k == MIX, 3, 2)
            # rows read in place: a function taking the stack would copy it (another 96 B of frame)
            v = _combine(T, node, k, s[first], s[first + 1], s[top - 1], uv, p, n)
            top = first
        s[top] = v
        top += 1
    return s[0]
