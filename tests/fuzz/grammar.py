"""A grammar-aware generator of hostile inputs (issue 32): scenes whose every directive is
well formed (right names, right parameter types, bracketed lists of the right kind) but whose
values are hostile (sizes, counts, indices, subdivision levels, nested and cyclic textures), so
mutants reach the builder, the upload and the device instead of dying in the tokenizer (about
nine mutants in ten of mutations.py do); image and mesh files whose headers lie about their
size; and checkpoints whose arrays hold values no render could.

Parameter names and types come from the plugins' own declarations (``renderer.materials`` and
``renderer.lights`` registries), so a new material or light is fuzzed without editing this file."""
from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np
from hypothesis import strategies as st

#: Well-formed numbers with hostile magnitudes (no nan/inf: the tokenizer refuses those, and the
#: point here is to get past it).
FLOATS = [0.0, -0.0, -1.0, 1e-45, 1e-30, 1e-6, 0.5, 1.0, 2.0, 1000.0, 1e6, 1e30, 3.4e38, 1e300, -1e300]
INTS = [0, 1, -1, 2, 3, 7, 64, 1000, 2**31 - 1, 2**31, 2**32, 10**9, 10**12]
#: What image and mesh headers claim, (width, height): plausible, empty and enormous.
CLAIMS = [(4, 2), (8, 8), (0, 0), (1, 100_000), (65_535, 65_535), (100_000, 50_000), (2**31 - 1, 2)]
IMAGE_FILES = ("img.png", "img.exr", "img.hdr", "img.tga", "img.pfm")
TEXTURE_NAMES = ("ta", "tb", "tc")
TEXTURE_KINDS = ("constant", "checkerboard", "scale", "mix", "directionmix", "imagemap", "fbm", "wrinkled",
                 "windy", "marble", "bilerp", "dots")


def _number(v: float | int) -> str:
    return repr(v) if isinstance(v, float) else str(v)


#: Plausible values, drawn two times in three so that most directives get past their range checks
#: and a scene reaches the device with a few hostile values in it
PLAIN_FLOATS = [0.1, 0.5, 1.0, 2.0]
PLAIN_INTS = [1, 2, 4]


@st.composite
def _values(draw, kind: str, n: int | None = None) -> str:
    """A bracketed list of ``n`` values of ``kind`` ("float", "int", "bool", "string"), each hostile
    one time in three; ``n`` drawn (a hostile length now and then) when not given."""
    if n is None:
        n = 1 if draw(st.integers(0, 7)) else draw(st.sampled_from([0, 2, 3, 12]))
    if kind == "bool":
        return "[" + " ".join(draw(st.sampled_from(["true", "false"])) for _ in range(n)) + "]"
    if kind == "string":
        return '["' + draw(st.sampled_from(["linear", "sRGB", "gamma 2.2", "repeat", "clamp", "black",
                                            "uv", "spherical", "planar", "img.png", "ta", "", "x" * 300])) + '"]'
    plain, hostile = (PLAIN_INTS, INTS) if kind == "int" else (PLAIN_FLOATS, FLOATS)
    return "[" + " ".join(_number(draw(st.sampled_from(hostile if draw(st.integers(0, 2)) == 0 else plain)))
                          for _ in range(n)) + "]"


#: pbrt parameter types for each declared plugin parameter type
_PBRT_TYPE = {"float": "float", "rgb": "rgb", "bool": "bool", "int": "integer", "string": "string",
              "strings": "string", "point3": "point3", "floats": "float", "points3": "point3"}


@st.composite
def _declared(draw, params) -> str:
    """Some of a plugin's declared parameters, each with its own type and a hostile value (a
    texture-capable one may name a texture, declared or not)."""
    chosen = draw(st.lists(st.sampled_from(sorted(params.by_name)), max_size=5, unique=True)) if params.by_name else []
    out = []
    for name in chosen:
        p = params.by_name[name]
        if p.texture and draw(st.booleans()):
            out.append(f'"texture {name}" "{draw(st.sampled_from(TEXTURE_NAMES + ("nope",)))}"')
            continue
        base = {"int": "int", "bool": "bool", "string": "string", "strings": "string"}.get(p.type, "float")
        count = {"rgb": 3, "point3": 3, "points3": 12}.get(p.type, 1 if p.type != "floats" else None)
        if draw(st.integers(0, 7)) == 0:
            count = None                           # a wrong count now and then
        out.append(f'"{_PBRT_TYPE[p.type]} {name}" {draw(_values(base, count))}')
    return " ".join(out)


@st.composite
def _material(draw) -> str:
    from renderer.materials import REGISTRY

    name = draw(st.sampled_from(sorted(REGISTRY)))
    return f'Material "{name}" {draw(_declared(REGISTRY[name].PARAMS))}'


@st.composite
def _light(draw) -> str:
    from renderer.lights import REGISTRY

    name = draw(st.sampled_from(sorted(n for n, m in REGISTRY.items() if m.DIRECTIVE == "LightSource")))
    extra = ""
    if name in ("infinite", "goniometric", "projection") and draw(st.booleans()):
        extra = f' "string filename" "{draw(st.sampled_from(IMAGE_FILES))}"'
    return f'LightSource "{name}" {draw(_declared(REGISTRY[name].PARAMS))}{extra}'


@st.composite
def _texture(draw) -> str:
    name = draw(st.sampled_from(TEXTURE_NAMES))
    kind = draw(st.sampled_from(TEXTURE_KINDS))
    value = draw(st.sampled_from(["float", "spectrum"]))
    ref = lambda: draw(st.sampled_from(TEXTURE_NAMES))          # earlier, later, itself: cycles too
    params = {
        "constant": lambda: f'"float value" {draw(_values("float"))}',
        "checkerboard": lambda: f'"float uscale" {draw(_values("float"))} "texture tex1" "{ref()}"',
        "scale": lambda: f'"texture tex" "{ref()}" "float scale" {draw(_values("float"))}',
        "mix": lambda: f'"texture tex1" "{ref()}" "texture tex2" "{ref()}" "texture amount" "{ref()}"',
        "directionmix": lambda: f'"texture tex1" "{ref()}" "texture tex2" "{ref()}" "vector3 dir" {draw(_values("float", 3))}',
        "imagemap": lambda: (f'"string filename" "{draw(st.sampled_from(IMAGE_FILES))}" '
                             f'"string wrap" {draw(_values("string"))} "bool invert" {draw(_values("bool"))}'),
        "fbm": lambda: f'"integer octaves" {draw(_values("int"))} "float roughness" {draw(_values("float"))}',
        "wrinkled": lambda: f'"integer octaves" {draw(_values("int"))}',
        "windy": lambda: "",
        "marble": lambda: f'"integer octaves" {draw(_values("int"))} "float variation" {draw(_values("float"))}',
        "bilerp": lambda: f'"float v00" {draw(_values("float"))} "float v11" {draw(_values("float"))}',
        "dots": lambda: f'"texture inside" "{ref()}" "texture outside" "{ref()}"',
    }[kind]()
    return f'Texture "{name}" "{value}" "{kind}" {params}'


@st.composite
def _shape(draw) -> str:
    kind = draw(st.sampled_from(["sphere", "cylinder", "disk", "trianglemesh", "bilinearmesh", "plymesh",
                                 "loopsubdiv"]))
    if kind in ("sphere", "cylinder", "disk"):
        return (f'Shape "{kind}" "float radius" {draw(_values("float"))} '
                f'"float phimax" {draw(_values("float"))}')
    if kind == "plymesh":
        return 'Shape "plymesh" "string filename" "m.ply"'
    n = draw(st.sampled_from([3, 4, 6]))
    P = " ".join(_number(draw(st.sampled_from(FLOATS))) for _ in range(3 * n))
    idx = " ".join(str(draw(st.sampled_from([0, 1, 2, 3, n - 1, n, -1, 2**31 - 1]))) for _ in range(
        draw(st.sampled_from([3, 4, 5, 6]))))
    levels = f' "integer levels" {draw(_values("int"))}' if kind == "loopsubdiv" else ""
    uv = f' "point2 uv" {draw(_values("float", 2 * n))}' if draw(st.booleans()) else ""
    return f'Shape "{kind}" "integer indices" [{idx}] "point3 P" [{P}]{uv}{levels}'


@st.composite
def _transform(draw) -> str:
    f = lambda: _number(draw(st.sampled_from(FLOATS)))
    return draw(st.sampled_from([
        f"Translate {f()} {f()} {f()}", f"Scale {f()} {f()} {f()}", f"Rotate {f()} {f()} {f()} {f()}",
        "ConcatTransform [" + " ".join(f() for _ in range(16)) + "]"]))


@st.composite
def _header(draw) -> list[str]:
    """Film, camera and sampler: hostile one time in eight, else valid, so that most scenes get
    past the header to the body's hostile values."""
    f = lambda: _number(draw(st.sampled_from(FLOATS)))
    if draw(st.integers(0, 15)) == 0:
        camera = draw(st.sampled_from([f'Camera "perspective" "float fov" [{f()}] "float lensradius" [{f()}]',
                                       f'Camera "orthographic" "float screenwindow" [{f()} {f()} {f()} {f()}]']))
        samples = draw(_values("int"))
    else:
        camera = draw(st.sampled_from(['Camera "perspective" "float fov" [40]', 'Camera "orthographic"',
                                       'Camera "spherical"', 'Camera "perspective" "float lensradius" [0.1] '
                                       '"float focaldistance" [3]']))
        samples = draw(st.sampled_from(["[1]", "[2]", "[4]"]))
    sampler = draw(st.sampled_from(["zsobol", "independent", "halton"]))
    return ['Film "rgb" "integer xresolution" [4] "integer yresolution" [3]', "LookAt 0 0 -5  0 0 0  0 1 0",
            camera, f'Sampler "{sampler}" "integer pixelsamples" {samples}']


@st.composite
def grammar_scene(draw) -> str:
    """A scene of well-formed directives with hostile values."""
    head = draw(_header()) + ["WorldBegin", 'LightSource "distant" "rgb L" [1 1 1]']
    directive = st.one_of(_material(), _light(), _texture(), _shape(), _transform(),
                          _shape().map(lambda s: 'AttributeBegin\nAreaLightSource "diffuse" "rgb L" [2 2 2]\n'
                                                 + s + "\nAttributeEnd"))
    block = st.lists(directive, min_size=1, max_size=4).map(lambda d: "\n".join(["AttributeBegin", *d,
                                                                                   "AttributeEnd"]))
    body = draw(st.lists(st.one_of(directive, block), min_size=1, max_size=8))
    return "\n".join(head + body + ['Shape "sphere"']) + "\n"


# ---- files whose headers lie ---------------------------------------------------------------------

def _png(w: int, h: int) -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        return len(data).to_bytes(4, "big") + kind + data + zlib.crc32(kind + data).to_bytes(4, "big")

    ihdr = (w % 2**32).to_bytes(4, "big") + (h % 2**32).to_bytes(4, "big") + bytes([8, 2, 0, 0, 0])
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\x00" * 64))
            + chunk(b"IEND", b""))


def _exr(w: int, h: int, tmp: Path) -> bytes:
    from renderer.io.images import write_exr

    write_exr(tmp / "seed.exr", np.full((2, 4, 3), 0.5, np.float32))
    data = (tmp / "seed.exr").read_bytes()
    at = data.index(b"dataWindow\x00box2i\x00") + len(b"dataWindow\x00box2i\x00") + 4
    corner = [0, 0, (w - 1) % 2**31, (h - 1) % 2**31]
    return data[:at] + struct.pack("<4i", *corner) + data[at + 16:]


def _hdr(w: int, h: int) -> bytes:
    return b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {h} +X {w}\n".encode() + b"\x80\x80\x80\x81" * 4


def _tga(w: int, h: int) -> bytes:
    return bytes([0, 0, 2]) + bytes(9) + struct.pack("<HH", w % 65536, h % 65536) + bytes([24, 0]) + b"\x7f" * 12


def _pfm(w: int, h: int) -> bytes:
    return f"PF\n{w} {h}\n-1.0\n".encode() + struct.pack("<3f", 0.5, 0.5, 0.5)


def _ply(n: int) -> bytes:
    return (f"ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\nproperty float y\n"
            f"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n").encode() \
        + struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + bytes([3]) + struct.pack("<3i", 0, 1, 2)


@st.composite
def lying_files(draw, tmp: Path) -> dict[str, bytes]:
    """Every image and mesh file a grammar scene may name, each claiming a drawn size."""
    out = {}
    for name, make in (("img.png", _png), ("img.hdr", _hdr), ("img.tga", _tga), ("img.pfm", _pfm)):
        out[name] = make(*draw(st.sampled_from(CLAIMS)))
    out["img.exr"] = _exr(*draw(st.sampled_from(CLAIMS)), tmp)
    out["m.ply"] = _ply(draw(st.sampled_from([3, 0, 2, 10**6, 2**31, 2**32 + 3])))
    return out


# ---- checkpoints that hold what no render could --------------------------------------------------

@st.composite
def hostile_state(draw, state: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """A real checkpoint's arrays with one to three of them given impossible or edge values."""
    out = {k: np.array(v) for k, v in state.items() if k != "sha256"}
    edge = [np.iinfo(np.int64).min, -1, 0, 1, 2**40, 2**62, 2**63 - 1]
    for _ in range(draw(st.integers(1, 3))):
        key = draw(st.sampled_from(["sum", "spp", "ranges", "bad", "rays", "seconds"]))
        if key == "sum":
            s = out["sum"].reshape(-1).copy()
            s[draw(st.integers(0, s.size - 1))] = draw(st.sampled_from(edge))
            out["sum"] = s.reshape(out["sum"].shape)
        elif key == "spp":
            out["spp"] = np.int64(draw(st.sampled_from([0, 1, 2, 3, 2**31 - 1])))
        elif key == "ranges":
            out["ranges"] = np.array(draw(st.sampled_from([[[0, 2]], [[0, 1], [1, 2]], [[0, 1], [0, 2]],
                                                           [[2, 0]], [[0, 2**40]], [[5, 7]]])), np.int64)
        elif key == "bad":
            out["bad"] = np.array([draw(st.sampled_from([0, -1, 10**9]))], np.int32)
        elif key == "rays":
            out["rays"] = np.array([draw(st.sampled_from([0.0, -1.0, 1e300]))])
        else:
            out["seconds"] = np.float64(draw(st.sampled_from([0.0, 1e300, -5.0])))
    return out
