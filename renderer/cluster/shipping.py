"""The scene as it travels to workers: the :class:`SceneDescription` plus the bytes of every file
the device upload reads, so a worker needs no shared file system and no copy of the scene folder.
A worker writes the files into a folder of its own and points the description at them."""
from __future__ import annotations

import dataclasses
from pathlib import Path

from renderer.io.fingerprint import referenced_files
from renderer.scene.description import SceneDescription
from renderer.scene.params import ParamSet

#: Each referenced file's bytes by its resolved path on the driver.
SceneFiles = dict[str, bytes]


def scene_files(desc: SceneDescription) -> SceneFiles:
    """The bytes of every file ``desc``'s upload reads (read once, on the driver)."""
    return {str(p): p.read_bytes() for p in referenced_files(desc)}


def localised(desc: SceneDescription, files: SceneFiles, folder: Path) -> tuple[SceneDescription, dict[str, str]]:
    """A copy of ``desc`` whose textures, environment images and NanoVDB media read the shipped ``files``,
    written under ``folder`` (one subfolder per file keeps names and suffixes as they were), and
    each written file's original path by its new one (so errors can name the file the user knows)."""
    local: dict[str, str] = {}
    for i, (original, data) in enumerate(files.items()):
        path = folder / str(i) / Path(original).name
        path.parent.mkdir(parents=True)
        path.write_bytes(data)
        local[original] = str(path)
    textures = {}
    for key, t in desc.textures.items():
        name = t.params.params.get("filename")
        if name is not None:
            moved = dataclasses.replace(name, values=[local[str((t.base_dir / str(name.values[0])).resolve())]])
            t = dataclasses.replace(t, params=ParamSet({**t.params.params, "filename": moved}, t.params.loc))
        textures[key] = t
    lights = [dataclasses.replace(light, values={**light.values,
                                                 "filename": local[str(Path(light.values["filename"]).resolve())]})
              if light.values.get("filename") is not None else light for light in desc.lights]
    media = [dataclasses.replace(m, filename=Path(local[str(m.filename.resolve())])) if m.filename is not None else m
             for m in desc.media]
    return dataclasses.replace(desc, textures=textures, lights=lights, media=media), {v: k for k, v in local.items()}
