"""Scene text written to a temporary folder and loaded, and the located-error check the parser tests
share: a refusal must name the file and line."""
from __future__ import annotations

from pathlib import Path

import pytest

from renderer.errors import Location, SceneError
from renderer.scene import load_description

DATA = Path(__file__).parent / "data" / "scenes"
HEAD = 'Camera "perspective"\nWorldBegin\n'          # two lines: scene text after it starts at line 3


def write(tmp_path: Path, text: str, name: str = "scene.pbrt") -> Path:
    path = tmp_path / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def load(tmp_path: Path, text: str):
    return load_description(write(tmp_path, text))


def error_at(tmp_path: Path, text: str, line: int, match: str, file: str = "scene.pbrt",
             kind: type[SceneError] = SceneError) -> SceneError:
    """Loading ``text`` fails with ``kind``, located at ``file``:``line``, message matching ``match``."""
    path = write(tmp_path, text)
    with pytest.raises(kind, match=match) as info:
        load_description(path)
    assert info.value.loc == Location(str(tmp_path / file), line), str(info.value)
    assert str(info.value).startswith(f"{tmp_path / file}:{line}: ")
    return info.value
