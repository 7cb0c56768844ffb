"""Tokens -> directives: each pbrt-v4 directive with its positional arguments, its typed
parameter list and its file:line. ``Include``/``Import`` are expanded here, in place (a ``.gz``
file gunzipped, as pbrt-v4 does), so the builder sees one flat stream whose locations still name
the file each directive came from.
``Import`` is read as ``Include``: pbrt-v4 only adds that an imported file may be parsed in
parallel and must not leave transforms changed, which a well-formed file does not do anyway."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

from renderer.errors import Location, MissingFileError, SceneError
from renderer.scene.compressed import TooLargeError, read_bytes
from renderer.scene.params import PARAM_TYPES, Param, ParamSet
from renderer.scene.tokenizer import Token, tokenize


@dataclass(frozen=True)
class Signature:
    """What follows a directive's name: ``args`` is one letter per positional argument
    ("s" quoted string, "o" optional quoted string, "w" bare word), ``numbers`` how many
    numbers (bracketed or not), ``params`` whether a parameter list may follow."""

    args: str = ""
    numbers: int = 0
    params: bool = False


#: Every directive of pbrt-v4 (plus pbrt-v3's WorldEnd, which is harmless): anything else is an error.
SIGNATURES: dict[str, Signature] = {
    **{d: Signature() for d in ("AttributeBegin", "AttributeEnd", "TransformBegin", "TransformEnd", "ObjectEnd",
                                "WorldBegin", "WorldEnd", "Identity", "ReverseOrientation")},
    **{d: Signature(numbers=k) for d, k in (("LookAt", 9), ("Translate", 3), ("Scale", 3), ("Rotate", 4),
                                            ("Transform", 16), ("ConcatTransform", 16), ("TransformTimes", 2))},
    **{d: Signature("s") for d in ("CoordinateSystem", "CoordSysTransform", "Include", "Import", "NamedMaterial",
                                   "ObjectBegin", "ColorSpace")},
    **{d: Signature("s", params=True) for d in ("Camera", "Film", "Sampler", "Integrator", "PixelFilter",
                                                "Accelerator", "Shape", "Material", "AreaLightSource", "LightSource",
                                                "MakeNamedMaterial", "MakeNamedMedium", "Attribute",
                                                "ObjectInstance")},
    "Texture": Signature("sss", params=True),
    "MediumInterface": Signature("so"),
    "ActiveTransform": Signature("w"),
    "Option": Signature(params=True),
}

#: pbrt-v4 spellings that mean the same as a type in PARAM_TYPES.
_TYPE_ALIASES = {"point": "point3", "vector": "vector3", "normal": "normal3", "color": "rgb"}
_NUMERIC_TYPES = {"integer", "float", "point2", "vector2", "point3", "vector3", "normal3", "rgb", "blackbody"}
_INT32_MIN, _INT32_MAX = -(1 << 31), (1 << 31) - 1
_TUPLE_SIZE = {"point2": 2, "vector2": 2, "point3": 3, "vector3": 3, "normal3": 3, "rgb": 3}


@dataclass
class Directive:
    name: str
    args: list[str | float] = field(default_factory=list)
    params: ParamSet = field(default_factory=ParamSet)
    loc: Location = Location("", 0)


#: Bounds on includes, as pbrt has none: nesting deeper than this is almost surely a mistake, and
#: a file including the next one twice, thirty deep, would otherwise expand to 2^30 files.
MAX_INCLUDE_DEPTH = 100
MAX_INCLUDED_FILES = 10_000
MAX_INCLUDED_BYTES = 1 << 30
#: Longer paths are shown shortened in messages (a path is never longer than the OS allows anyway).
_MAX_SHOWN_PATH = 200


@dataclass
class _IncludeBudget:
    """What the includes of one top-level file have used so far, shared by every nested file."""

    files: int = 0
    bytes: int = 0


def shown_path(path: str | Path) -> str:
    """A path as messages show it: a hostile 1 MB name is cut to its start and end."""
    s = str(path)
    return s if len(s) <= _MAX_SHOWN_PATH else f"{s[:100]}...{s[-60:]} ({len(s)} characters)"


def require_file(path: Path, loc: Location | None, what: str) -> Path:
    """``path`` when it is a file; else a MissingFileError, or a SceneError for a path the system
    refuses outright (a name too long), each showing the path shortened."""
    try:
        found = path.is_file()
    except OSError as e:
        raise SceneError(f"cannot open {what} {shown_path(path)}: {e.strerror or e}", loc) from None
    if not found:
        raise MissingFileError(shown_path(path), loc, what)
    return path


def parse_file(path: str | Path, chain: tuple[Path, ...] = (), included_at: Location | None = None,
               budget: _IncludeBudget | None = None) -> Iterator[Directive]:
    """Yield the directives of ``path`` with its includes expanded. Include paths resolve against
    the folder of the file that names them; ``chain`` (the files including this one) catches a
    file that includes itself, directly or not; ``included_at`` locates errors about the file;
    ``budget`` bounds the total number and size of included files."""
    path = Path(path)
    budget = _IncludeBudget() if budget is None else budget
    text = _read_scene_text(path, included_at, budget)
    key = path.resolve()
    if key in chain:
        raise SceneError(f"include cycle: {' -> '.join(p.name for p in (*chain, key))}", included_at)
    if len(chain) >= MAX_INCLUDE_DEPTH:
        raise SceneError(f"includes nested more than {MAX_INCLUDE_DEPTH} deep", included_at)
    for d in _Parser(tokenize(text, str(path))).directives():
        if d.name in ("Include", "Import"):
            budget.files += 1
            if budget.files > MAX_INCLUDED_FILES:
                raise SceneError(f"more than {MAX_INCLUDED_FILES} files included in all (does a file include "
                                 "another several times, over and over?)", d.loc)
            yield from parse_file(path.parent / str(d.args[0]), (*chain, key), d.loc, budget)
        else:
            yield d


def _read_scene_text(path: Path, included_at: Location | None, budget: _IncludeBudget) -> str:
    """The file's text, gunzipped when its name ends in ``.gz`` (as pbrt-v4 reads it); its
    (decompressed) size counts against the includes' budget. Bytes that are not UTF-8 are kept as
    surrogates for the tokenizer to locate."""
    require_file(path, included_at, "scene file")
    left = MAX_INCLUDED_BYTES - budget.bytes
    try:
        data = read_bytes(path, left, included_at, "scene file")
    except TooLargeError:
        raise SceneError(f"scene files exceed {MAX_INCLUDED_BYTES >> 20} MiB in all", included_at) from None
    budget.bytes += len(data)
    return data.decode("utf-8", errors="surrogateescape")


class _Parser:
    """A one-token look-ahead reader over a token stream."""

    def __init__(self, tokens: Iterator[Token]):
        self._tokens = tokens
        self._next: Token | None = next(tokens, None)
        self._last_loc = self._next.loc if self._next else None

    def _peek(self) -> Token | None:
        return self._next

    def _take(self, what: str) -> Token:
        t = self._next
        if t is None:
            raise SceneError(f"unexpected end of file: expected {what}", self._last_loc)
        self._last_loc = t.loc
        self._next = next(self._tokens, None)
        return t

    def directives(self) -> Iterator[Directive]:
        while (t := self._peek()) is not None:
            self._take("a directive")
            if t.kind != "word":
                raise SceneError(f"expected a directive, found {_describe(t)}", t.loc)
            sig = SIGNATURES.get(str(t.value))
            if sig is None:
                raise SceneError(f'unknown directive "{t.value}"', t.loc)
            d = Directive(str(t.value), loc=t.loc)
            d.params.loc = t.loc
            for a in sig.args:
                nxt = self._peek()
                if a == "o" and (nxt is None or nxt.kind != "string"):
                    continue
                arg = self._take(f"an argument of {d.name}")
                want = "word" if a == "w" else "string"
                if arg.kind != want:
                    kind = "a quoted string" if want == "string" else "a name"
                    raise SceneError(f"{d.name} expects {kind}, found {_describe(arg)}", arg.loc)
                d.args.append(str(arg.value))
            if sig.numbers:
                d.args.extend(self._numbers(d.name, sig.numbers, t.loc))
            if sig.params:
                while (p := self._peek()) is not None and p.kind == "string":
                    d.params.add(self._param())
            yield d

    def _numbers(self, directive: str, count: int, loc: Location) -> list[float]:
        """Exactly ``count`` numbers, optionally in brackets (pbrt writes Transform's in brackets)."""
        t = self._peek()
        if t is not None and t.kind == "[":
            self._take("[")
            values = self._bracketed(t.loc)
        else:
            values = []
            while len(values) < count and (t := self._peek()) is not None and _is_value(t):
                values.append(self._take("a number"))
        for v in values:
            if v.kind != "number":
                raise SceneError(f"{directive}: bad number {_describe(v)}", v.loc)
        if len(values) != count:
            raise SceneError(f"{directive} needs {count} numbers, got {len(values)}", loc)
        return [float(v.value) for v in values]

    def _bracketed(self, open_loc: Location) -> list[Token]:
        values: list[Token] = []
        while True:
            t = self._peek()
            if t is None or not _is_value(t):
                raise SceneError('unterminated "[": no matching "]"', open_loc)
            self._take("]")
            if t.kind == "]":
                return values
            if t.kind == "[":
                raise SceneError('unexpected "[" inside brackets', t.loc)
            values.append(t)

    def _param(self) -> Param:
        decl = self._take("a parameter")
        words = str(decl.value).split()
        if len(words) != 2:
            raise SceneError(f'bad parameter declaration "{decl.value}": expected "type name"', decl.loc)
        ptype, name = _TYPE_ALIASES.get(words[0], words[0]), words[1]
        if ptype not in PARAM_TYPES:
            raise SceneError(f'unknown parameter type "{words[0]}" for "{name}"', decl.loc)
        t = self._peek()
        if t is None or t.kind == "]" or not _is_value(t):
            raise SceneError(f'parameter "{name}" has no value', decl.loc)
        self._take("a value")
        tokens = self._bracketed(t.loc) if t.kind == "[" else [t]
        return Param(ptype, name, _values(ptype, name, tokens, decl.loc), decl.loc)


def _values(ptype: str, name: str, tokens: list[Token], loc: Location) -> list:
    """Check the values' kinds against the declared type and convert them."""
    def bad(t: Token, expected: str) -> SceneError:
        return SceneError(f'parameter "{name}" ({ptype}) expects {expected}, found {_describe(t)}', t.loc)

    if ptype in _NUMERIC_TYPES or (ptype == "spectrum" and not any(t.kind == "string" for t in tokens)):
        for t in tokens:
            if t.kind != "number":
                raise bad(t, "numbers")
            if ptype == "integer" and not isinstance(t.value, int):
                raise bad(t, "integers")
            if ptype == "integer" and not _INT32_MIN <= t.value <= _INT32_MAX:
                raise bad(t, "32-bit integers (as pbrt's are)")
        if len(tokens) % _TUPLE_SIZE.get(ptype, 1):
            raise SceneError(f'parameter "{name}" ({ptype}) needs a multiple of {_TUPLE_SIZE[ptype]} values, '
                             f'got {len(tokens)}', loc)
        return [t.value for t in tokens]
    if ptype == "bool":
        for t in tokens:
            if t.value not in ("true", "false"):
                raise bad(t, "true or false")
        return [t.value == "true" for t in tokens]
    for t in tokens:                     # string, texture, named or file spectrum
        if t.kind != "string":
            raise bad(t, "a quoted string")
    if ptype == "spectrum" and len(tokens) != 1:
        raise SceneError(f'parameter "{name}": a named or file spectrum takes one string', loc)
    return [t.value for t in tokens]


def _is_value(t: Token) -> bool:
    """Whether a token can stand as a value: a bare word counts unless it names a directive, so
    ``4.5.6`` is reported as a bad number but a missing value as a missing value."""
    return t.kind != "word" or t.value not in SIGNATURES


def _describe(t: Token) -> str:
    return f'"{t.value}"' if t.kind in ("string", "word") else str(t.value)
