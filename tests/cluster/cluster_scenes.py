"""A tiny pbrt scene for the cluster tests with what a cluster render must carry: thin-film
spheres, an instanced object, an environment image and an image texture (files the workers get
through Ray's object store, not the file system)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from renderer.io.images import write_exr, write_png

SCENE = """LookAt 0 1.2 -5  0 0.4 0  0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [24] "integer yresolution" [16] "string filename" ["cluster.exr"]
Sampler "independent" "integer pixelsamples" [6] "integer seed" [5]
Integrator "path" "integer maxdepth" [6]
WorldBegin
LightSource "infinite" "string filename" ["maps/sky.exr"]
Texture "checks" "spectrum" "imagemap" "string filename" ["maps/ground.png"]
AttributeBegin
  Material "diffuse" "texture reflectance" "checks"
  Shape "bilinearmesh" "point3 P" [-3 0 -3  3 0 -3  -3 0 3  3 0 3] "point2 uv" [0 0 1 0 0 1 1 1]
AttributeEnd
AttributeBegin
  Material "thinfilm" "float eta_outer" [1] "float eta_film" [1.5] "float eta_inner" [1.7] "float thickness" [420]
  Translate -0.8 0.6 0
  Shape "sphere" "float radius" [0.6]
AttributeEnd
ObjectBegin "pebble"
  Material "conductor"
  Shape "sphere" "float radius" [0.25]
ObjectEnd
AttributeBegin
  Translate 0.8 0.25 -0.4
  ObjectInstance "pebble"
  Translate 0.3 0 0.6
  ObjectInstance "pebble"
AttributeEnd
"""


def write_cluster_scene(folder: Path) -> Path:
    """The scene and its two image files under ``folder``; returns the scene file."""
    maps = folder / "maps"
    maps.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(3)
    sky = np.linspace(0.2, 1.5, 8, dtype=np.float32)[:, None, None] * rng.uniform(0.5, 1.0, (8, 16, 3))
    write_exr(maps / "sky.exr", sky.astype(np.float32))
    checks = np.kron((np.indices((4, 4)).sum(axis=0) % 2)[..., None], np.ones((4, 4, 1))) * 0.6 + 0.2
    write_png(maps / "ground.png", np.repeat(checks, 3, axis=2).astype(np.float32))
    path = folder / "cluster.pbrt"
    path.write_text(SCENE)
    return path
