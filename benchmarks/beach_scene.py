"""What the beach's geometry benchmarks (conch_pose.py, lens_reflection.py) read from the scene:
the camera, the sun and the recipe's entries, as the renderer and the recipe read them, so a scene
edit never leaves a stale copy in a script; and a Warp any-hit ray cast against one mesh.
Needs the beach's assets (``assets-gen recipe scenes/beach.pbrt``) for the sun.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
import trimesh
import warp as wp

ROOT = Path(__file__).resolve().parents[1]
os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".warp-cache"))

from assets_gen.recipe import load as recipe_entries  # noqa: E402
from renderer.scene import load_description  # noqa: E402
from renderer.scene.description import SceneDescription  # noqa: E402

SCENES = ROOT / "scenes"
ASSETS = SCENES / "assets" / "beach"


def load_fragment(path: Path) -> SceneDescription:
    """A scene file that holds only directives after WorldBegin (materials, lights), loaded through
    a scene that includes it, so its relative paths resolve against its own folder."""
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "fragment.pbrt"
        scene.write_text(f'WorldBegin\nInclude "{path}"\n')
        return load_description(scene)


def camera_eye() -> np.ndarray:
    """The beach camera's position (world, m)."""
    return load_description(SCENES / "parts" / "beach_camera_view.pbrt").camera.camera_to_world[:3, 3]


def sun_direction() -> np.ndarray:
    """Unit world direction towards the sun: the distant light the recipe's sky-lights step writes."""
    sun = next(x for x in load_fragment(ASSETS / "lights" / "lights.pbrt").lights if x.kind == "distant")
    m = sun.light_to_world
    d = (m[:3, :3] @ (np.asarray(sun.values["from"], float) - np.asarray(sun.values["to"], float)))
    return d / np.linalg.norm(d)


def recipe_params(entry: str) -> dict:
    """The ``params`` of one entry of scenes/beach.recipe.json, validated by the recipe loader (as
    written: the final level)."""
    return next(e.params for e in recipe_entries(SCENES / "beach.recipe.json") if e.name == entry)


@wp.kernel
def _any_hit(mesh: wp.uint64, o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.int32)):
    i = wp.tid()
    if wp.mesh_query_ray(mesh, o[i], d[i], 10.0).result:
        out[i] = 1


def blocked(m: trimesh.Trimesh, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Whether each ray (o, d) hits ``m`` within 10 m."""
    mesh = wp.Mesh(points=wp.array(m.vertices.astype(np.float32), dtype=wp.vec3),
                   indices=wp.array(m.faces.astype(np.int32).ravel(), dtype=wp.int32))
    out = wp.zeros(len(o), dtype=wp.int32)
    wp.launch(_any_hit, len(o), [mesh.id, wp.array(o.astype(np.float32), dtype=wp.vec3),
                                 wp.array(d.astype(np.float32), dtype=wp.vec3), out])
    return out.numpy() > 0
