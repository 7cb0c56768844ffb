"""volpath against closed forms: a white furnace inside a scattering medium (albedo 1 in every
channel, chromatic sigma_t, anisotropic phase) under a uniform sky renders 1 in every channel, and
with albedo a < 1 seen through an absorbing-only shell, exp(-sigma_a R) exactly."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from renderer.api import load_scene, render

SCENE = """MediumInterface "" "inner"
LookAt 0 0 0  0 0 1  0 1 0
Camera "perspective" "float fov" 60
Sampler "independent"
Integrator "volpath" "integer maxdepth" 400
Film "rgb" "integer xresolution" 12 "integer yresolution" 12 "string filename" "f.exr"
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
MakeNamedMedium "inner" "string type" "homogeneous" "rgb sigma_a" [{sa}] "rgb sigma_s" [{ss}] "float g" {g}
AttributeBegin
MediumInterface "inner" ""
Material "interface"
Shape "sphere" "float radius" 1
AttributeEnd
"""


def furnace(tmp_path: Path, sa: str, ss: str, g: float, spp: int = 256) -> np.ndarray:
    (tmp_path / "f.pbrt").write_text(SCENE.format(sa=sa, ss=ss, g=g))
    return render(load_scene(tmp_path / "f.pbrt"), spp=spp, seed=4)


def test_white_furnace_in_a_chromatic_scattering_medium(tmp_path):
    img = furnace(tmp_path, "0 0 0", "0.5 2 4", 0.6).reshape(-1, 3)
    mean, se = img.mean(0), img.std(0) / np.sqrt(len(img))
    assert np.all(np.abs(mean - 1) < 4 * se + 2e-3), (mean, se)


def test_absorbing_sphere_seen_from_its_centre_is_beer_lambert(tmp_path):
    sa = np.array([0.3, 0.9, 2.0])
    img = furnace(tmp_path, "0.3 0.9 2", "0 0 0", 0.0, spp=64).reshape(-1, 3)
    np.testing.assert_allclose(img.mean(0), np.exp(-sa * 1.0), rtol=2e-2)
