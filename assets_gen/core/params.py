"""Parameters as frozen dataclasses, so the CLI, the recipe and tests share one declaration:
each field carries its default, its help (with the unit) and whether it names an input file."""
from __future__ import annotations

import contextlib
import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator, Mapping, TypeVar

P = TypeVar("P", bound="Params")


class GeneratorError(ValueError):
    """A bad generator parameter; the CLI prints it on one line and exits with code 2."""


@contextlib.contextmanager
def reading(path: str | Path, what: str) -> Iterator[None]:
    """Turn a failure to read or parse an input file into a :class:`GeneratorError` naming it:
    readers (OpenEXR, trimesh, Pillow, json) raise their own exception types for a bad file."""
    try:
        yield
    except GeneratorError:
        raise
    except KeyError as e:   # a parsed file without an entry the reader needs (json's bare 'key' says little)
        raise GeneratorError(f"cannot read {what} {str(path)!r}: it has no {e.args[0]!r} entry") from e
    except Exception as e:  # the block holds only the read, so nothing else is masked
        raise GeneratorError(f"cannot read {what} {str(path)!r}: {e}") from e


def require(cond: bool, message: str) -> None:
    """Raise :class:`GeneratorError` with ``message`` unless ``cond`` holds."""
    if not cond:
        raise GeneratorError(message)


def param(default: Any, help: str, *, choices: tuple[str, ...] | None = None, path: bool = False) -> Any:
    """A parameter field. ``help`` names the unit; ``choices`` limits a string; ``path`` marks a
    file or folder the generator reads (resolved against the caller's base folder, hashed by recipes)."""
    meta: dict[str, Any] = {"help": help, "path": path}
    if choices is not None:
        meta["choices"] = tuple(choices)
    return field(default=default, metadata=meta)


def kind(f: dataclasses.Field) -> type:
    """The value type of a parameter field: that of its default (bool, int, float, str or tuple)."""
    return type(f.default)


@dataclass(frozen=True)
class Params:
    """Base of every generator's parameter dataclass."""

    def __post_init__(self) -> None:
        """Values take their field's type, however they were given (CLI, JSON, Python): an int for a
        float becomes a float, a list a tuple, so the same parameters give the same manifest; values
        of another type raise :class:`GeneratorError` naming the field."""
        for f in dataclasses.fields(self):
            object.__setattr__(self, f.name, _coerce(f, getattr(self, f.name)))

    def validate(self) -> None:
        """Raise :class:`GeneratorError` for a value out of range (after input paths are resolved)."""

    @classmethod
    def from_dict(cls: type[P], values: Mapping[str, Any]) -> P:
        """The parameters from plain values (a recipe's JSON); an unknown key raises
        :class:`GeneratorError` naming it."""
        known = sorted(f.name for f in dataclasses.fields(cls))
        unknown = sorted(set(values) - set(known))
        require(not unknown, f"unknown parameter(s) {unknown}; known: {known}")
        return cls(**values)

    def resolved(self: P, base: Path) -> P:
        """A copy with relative input paths made relative to ``base`` instead of the working folder."""
        return dataclasses.replace(self, **{
            f.name: str(Path(base) / v) for f in dataclasses.fields(self)
            if f.metadata.get("path") and (v := getattr(self, f.name)) and not Path(v).is_absolute()})

    def input_paths(self) -> list[str]:
        """The non-empty values of the fields that name input files or folders."""
        return [v for f in dataclasses.fields(self) if f.metadata.get("path") and (v := getattr(self, f.name))]

    def as_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def _coerce(f: dataclasses.Field, value: Any) -> Any:
    want = kind(f)
    bad = GeneratorError(f"parameter {f.name!r}: expected {_describe(f)}, got {value!r}")
    if want is bool:
        if not isinstance(value, bool):
            raise bad
    elif want is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise bad
    elif want is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise bad
        value = float(value)
        if not math.isfinite(value):
            raise GeneratorError(f"parameter {f.name!r}: expected a finite number, got {value!r}")
    elif want is str:
        if not isinstance(value, str):
            raise bad
        if "choices" in f.metadata and value not in f.metadata["choices"]:
            raise GeneratorError(f"parameter {f.name!r}: {value!r} is not one of {list(f.metadata['choices'])}")
    elif want is tuple:
        if (not isinstance(value, (list, tuple)) or len(value) != len(f.default)
                or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value)):
            raise bad
        value = tuple(float(v) for v in value)
        if not all(math.isfinite(v) for v in value):
            raise GeneratorError(f"parameter {f.name!r}: expected finite numbers, got {list(value)}")
    return value


def _describe(f: dataclasses.Field) -> str:
    want = kind(f)
    if want is tuple:
        return f"a list of {len(f.default)} numbers"
    return {bool: "true or false", int: "an integer", float: "a number", str: "a string"}[want]
