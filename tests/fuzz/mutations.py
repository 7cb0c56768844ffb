"""Hypothesis strategies that mutate valid inputs into hostile ones: pbrt scene text token by
token, binary files byte by byte and by their declared counts, and ``render`` command lines.

The seeds are real inputs (every scene in ``scenes/`` and ``tests/data``, small scenes of each
feature, files the renderer itself writes), so most mutants stay close to something that parses
and reach the checks behind the tokenizer rather than dying at the first character."""
from __future__ import annotations

import re
from pathlib import Path

from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[2]

#: Numbers and strings that have broken parsers before (issue 17's list and their neighbours).
HOSTILE_NUMBERS = ["0", "-0", "-1", "1e400", "-1e400", "1e38", "3.5e38", "1e-45", "nan", "inf", "-inf",
                   "4294967296", "2147483648", "-2147483649", "99999999999999999999999", "9" * 400,
                   "0x10", "1e", "--1", ".", "1.5.5", "1000000000"]
HOSTILE_STRINGS = ['""', '"../../../../etc/passwd"', '"' + "a" * 5000 + '"', '"\u00e9\u00e8"', '"nul\\0"',
                   '"gamma abc"', '"gamma -1"', '"scenes"', '"/dev/zero"', '"x.ply.gz"', '"spectral:100000000"']
HOSTILE_TOKENS = ["[", "]", "[ ]", "WorldBegin", "AttributeEnd", "ObjectEnd", "Include", '"float"', '"rgb L"',
                  'Include "self.pbrt"', "ObjectInstance", "Shape", '"string filename"', "#", "\ufeff"]

#: Small scenes of each feature, so mutations reach every directive even without generated assets.
FEATURE_SCENES = [
    'Film "rgb" "integer xresolution" [6] "integer yresolution" [4]\nCamera "perspective" "float fov" [40]\n'
    'Sampler "independent"\nWorldBegin\nLightSource "infinite" "rgb L" [1 1 1]\n'
    'Material "dielectric" "float eta" [1.5]\nShape "sphere" "float radius" [0.5]\n',
    'Camera "perspective"\nWorldBegin\nAttributeBegin\nAreaLightSource "diffuse" "blackbody L" [5500]\n'
    'Shape "trianglemesh" "integer indices" [0 1 2] "point3 P" [0 0 2 1 0 2 0 1 2]\nAttributeEnd\n'
    'Texture "t" "spectrum" "checkerboard" "float uscale" [4] "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]\n'
    'Material "diffuse" "texture reflectance" "t"\nShape "sphere"\n',
    'Camera "perspective"\nWorldBegin\nLightSource "distant" "point3 from" [0 1 0] "rgb L" [3 3 3]\n'
    'MakeNamedMaterial "film" "string type" "thinfilm" "float thickness" [400] "float eta_film" [1.33]\n'
    'ObjectBegin "o"\nNamedMaterial "film"\nShape "sphere" "float radius" [0.2]\nObjectEnd\n'
    'Translate 0 0 1\nObjectInstance "o"\nRotate 30 0 1 0\nScale 2 2 2\nObjectInstance "o"\n',
    'Camera "perspective"\nWorldBegin\nLightSource "spot" "point3 from" [0 2 0] "point3 to" [0 0 0] '
    '"float coneangle" [30]\nLightSource "point" "rgb I" [2 2 2]\n'
    'Material "conductor" "float roughness" [0.2]\nShape "sphere"\nMaterial "disney" "rgb color" [0.8 0.7 0.5] '
    '"float subsurface" [0.5]\nTranslate 0 -1 0\nShape "sphere"\n',
]

_TOKEN = re.compile(r'"[^"\n]*"|\[|\]|[^\s\[\]"]+')
_LINE = re.compile(r'"[^"\n]*"|#.*|[^"#]+|"')


def _uncommented(text: str) -> str:
    """``text`` without its comments (a ``#`` outside a string, to the end of the line)."""
    return "\n".join("".join(t for t in _LINE.findall(line) if not t.startswith("#")) for line in text.splitlines())


def seed_scenes() -> list[tuple[str, Path]]:
    """(text, folder it was read from) for every seed scene; relative paths resolve in that folder."""
    found = [(p.read_text(errors="replace"), p.parent) for p in sorted((ROOT / "scenes").glob("*.pbrt"))]
    found += [(p.read_text(errors="replace"), p.parent) for p in sorted((ROOT / "tests" / "data").rglob("*.pbrt"))]
    return found + [(text, ROOT / "tests" / "data" / "scenes") for text in FEATURE_SCENES]


@st.composite
def mutated_scene(draw, seeds: list[tuple[str, Path]]) -> tuple[str, Path]:
    """A seed scene with one to three token edits: delete, duplicate, swap, or replace a token by a
    hostile number, string or directive."""
    text, folder = draw(st.sampled_from(seeds))
    tokens = _TOKEN.findall(_uncommented(text)) or ["WorldBegin"]
    for _ in range(draw(st.integers(1, 3))):
        i = draw(st.integers(0, len(tokens) - 1))
        op = draw(st.sampled_from(["delete", "duplicate", "swap", "number", "string", "token"]))
        if op == "delete" and len(tokens) > 1:
            del tokens[i]
        elif op == "duplicate":
            tokens.insert(i, tokens[i])
        elif op == "swap":
            j = draw(st.integers(0, len(tokens) - 1))
            tokens[i], tokens[j] = tokens[j], tokens[i]
        elif op == "number":
            tokens[i] = draw(st.sampled_from(HOSTILE_NUMBERS))
        elif op == "string":
            tokens[i] = draw(st.sampled_from(HOSTILE_STRINGS))
        else:
            tokens.insert(i, draw(st.sampled_from(HOSTILE_TOKENS)))
    return "\n".join(tokens) + "\n", folder     # one token per line: an inserted "#" hides only itself


@st.composite
def mutated_bytes(draw, data: bytes) -> bytes:
    """``data`` truncated, with bytes overwritten, or with a declared count (the first run of
    digits after a byte offset) replaced by a huge one: what lying headers look like."""
    op = draw(st.sampled_from(["truncate", "flip", "count", "append"]))
    if op == "truncate":
        return data[:draw(st.integers(0, max(0, len(data) - 1)))]
    if op == "flip":
        out = bytearray(data)
        for _ in range(draw(st.integers(1, 8))):
            if out:
                out[draw(st.integers(0, len(out) - 1))] = draw(st.integers(0, 255))
        return bytes(out)
    if op == "count":
        start = draw(st.integers(0, max(0, len(data) - 1)))
        m = re.compile(rb"\d+").search(data, start)
        if m:
            big = draw(st.sampled_from([b"0", b"999999999", b"4294967296", b"99999999999999999999"]))
            return data[:m.start()] + big + data[m.end():]
        return data
    return data + draw(st.binary(min_size=1, max_size=64))


#: ``render`` options with values that are valid, at the edge, or wrong.
FLAG_VALUES = {
    "--spp": ["1", "2", "0", "-1", "nan", "1e9", "x"],
    "--res": ["4x3", "0x0", "1x1", "-4x3", "40000x40000", "4", "axb"],
    "--seed": ["0", "7", "-1", "4294967296", "2147483647"],
    "--max-depth": ["0", "1", "5", "-3", "4294967296"],
    "--exposure": ["0", "2", "-64", "64", "2000", "nan", "inf"],
    "--thin-film": ["rgb3", "spectral:4", "spectral:0", "spectral:100000000", "spectral:", "bogus"],
    "--time-limit": ["0", "0.5", "-1", "nan"],
    "--threads": ["1", "2", "0", "-2", "100000"],
    "--aov": ["normal", "albedo", "bogus"],
    "--reference": ["nope.exr"],
    "--resume": ["nope.npz"],
}


@st.composite
def render_flags(draw) -> list[str]:
    """A few options from :data:`FLAG_VALUES`, each at most once, in a random order."""
    names = draw(st.lists(st.sampled_from(sorted(FLAG_VALUES)), max_size=4, unique=True))
    argv: list[str] = []
    for name in names:
        argv += [name, draw(st.sampled_from(FLAG_VALUES[name]))]
    return argv
