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
#: Bytes that are not UTF-8, as ``errors="surrogateescape"`` decodes them: allowed in comments only.
_UNDECODED = re.compile("[\udc80-\udcff]")


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
            if _NUMBER.fullmatch(word):
                yield Token("number", _number(word, loc), loc)
            else:
                yield Token("word", _checked_text(word, loc), loc)
            i = j


def _number(word: str, loc: Location) -> int | float:
    """An int when written without a fraction or exponent, else a float; either must be finite
    as a double (``1e400`` or a 400-digit integer is refused here, with its line)."""
    value = float(word)
    if value in (float("inf"), float("-inf")):
        shown = word if len(word) <= 40 else f"{word[:20]}...({len(word)} characters)"
        raise SceneError(f"number {shown} is out of range (beyond double precision)", loc)
    return int(word) if _INTEGER.fullmatch(word) else value


def _checked_text(value: str, loc: Location) -> str:
    """Refuse bytes that are not UTF-8 outside comments (pbrt reads UTF-8; Latin-1 in comments is fine)."""
    if _UNDECODED.search(value):
        raise SceneError("the file is not valid UTF-8 here (only comments may hold other bytes)", loc)
    return value


def _string(text: str, start: int, loc: Location) -> tuple[int, str]:
    """Read the quoted string opening at ``start``; return the index after it and its value."""
    out: list[str] = []
    i = start + 1
    while i < len(text):
        c = text[i]
        if c == '"':
            return i + 1, _checked_text("".join(out), loc)
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
