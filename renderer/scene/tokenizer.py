"""Split a pbrt-v4 file into located tokens, so that every later error can say file:line."""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Iterator

from renderer.errors import Location, SceneError

#: A number as pbrt writes them; "nan" or "inf" are deliberately not numbers.
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_INTEGER = re.compile(r"[+-]?\d+")
_ESCAPES = {"b": "\b", "f": "\f", "n": "\n", "r": "\r", "t": "\t", "\\": "\\", "'": "'", '"': '"'}
_DELIMITERS = ' \t\r\n"[]#'


@dataclass(frozen=True)
class Token:
    """``kind`` is "string" (quoted), "number", "word" (an unquoted identifier), "[" or "]"."""

    kind: str
    value: str | int | float
    loc: Location


def tokenize(text: str, file: str) -> Iterator[Token]:
    """Yield the tokens of ``text``; ``file`` only labels locations. Numbers become int when
    written without a fraction or exponent, so ``integer`` parameters can insist on it."""
    i, line, n = 0, 1, len(text)
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
            i += 1
        elif c in " \t\r":
            i += 1
        elif c == "#":
            end = text.find("\n", i)
            i = n if end < 0 else end
        elif c in "[]":
            yield Token(c, c, Location(file, line))
            i += 1
        elif c == '"':
            i, value = _string(text, i, Location(file, line))
            yield Token("string", value, Location(file, line))
        else:
            j = i
            while j < n and text[j] not in _DELIMITERS:
                j += 1
            word = text[i:j]
            loc = Location(file, line)
            if _INTEGER.fullmatch(word):
                yield Token("number", int(word), loc)
            elif _NUMBER.fullmatch(word):
                yield Token("number", float(word), loc)
            else:
                yield Token("word", word, loc)
            i = j


def _string(text: str, start: int, loc: Location) -> tuple[int, str]:
    """Read the quoted string opening at ``start``; return the index after it and its value."""
    out: list[str] = []
    i = start + 1
    while i < len(text):
        c = text[i]
        if c == '"':
            return i + 1, "".join(out)
        if c == "\n":
            raise SceneError("unterminated string (a string may not span lines)", loc)
        if c == "\\":
            i += 1
            if i >= len(text) or text[i] not in _ESCAPES:
                esc = text[i] if i < len(text) else "end of file"
                raise SceneError(f"unknown escape sequence \\{esc} in string", loc)
            out.append(_ESCAPES[text[i]])
        else:
            out.append(c)
        i += 1
    raise SceneError("unterminated string at end of file", loc)
