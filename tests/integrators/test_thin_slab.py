"""Shadow rays through thin coated lenses (renderer.integrators.thin_slab): a flat coated, tinted
slab (2 mm, n 1.52) over a diffuse plane lit by a distant light.

- Closed form: under a delta sun and direct light only, the plane's radiance under the slab over
  the open plane's is T(θ) = T_coat(θ) · tint^(1/cos θ_t) · T_bare(θ), the coating's T from an
  independent transfer-matrix computation, the bare face's from Fresnel's equations.
- An opaque slab's shadow stays black with thin slabs in the scene.
- Nothing counted twice: under a soft sun (which BSDF sampling can reach through the slab's real
  refractions) next-event estimation with MIS agrees with BSDF sampling alone."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from optics.test_optics import tmm_RT
from renderer.api import load_scene, render
from renderer.device.scene import upload

TINT = np.array([0.40, 0.45, 0.38])
RGB3_NM = np.array([650.0, 510.0, 475.0])
SUN = np.array([0.6, 1.5, 0.8])
ETA, FILM_ETA, FILM_NM = 1.52, 1.38, 300.0

SCENE = """LookAt 0 0.5 -1.2  0 0 0  0 1 0
Camera "perspective" "float fov" 20
Sampler "independent" "integer pixelsamples" 4
Integrator "path" "integer maxdepth" {depth}
PixelFilter "box"
Film "rgb" "integer xresolution" 8 "integer yresolution" 8 "string filename" "slab.exr"
WorldBegin
LightSource "distant" "point3 from" [{sun}] "point3 to" [0 0 0] "rgb L" [2 2 2] "float angularradius" {radius}
MakeNamedMaterial "coated" "string type" "thinfilm" "float eta_film" {film_eta} "float thickness" {film_nm}
    "float eta_inner" {eta} "bool transmission" true "rgb tint" [{tint}] "bool thinslab" {slab}
MakeNamedMaterial "bare" "string type" "thinfilm" "float thickness" 0 "float eta_inner" {eta}
    "bool transmission" true "rgb tint" [{tint}] "bool thinslab" {slab}
MakeNamedMaterial "ground" "string type" "diffuse" "rgb reflectance" [0.5 0.5 0.5]
MakeNamedMaterial "opaque" "string type" "diffuse" "rgb reflectance" [0.5 0.5 0.5]
NamedMaterial "ground"
Shape "trianglemesh" "point3 P" [-20 0 -20  20 0 -20  20 0 20  -20 0 20] "integer indices" [0 1 2 0 2 3]
{slab_shapes}
"""
#: a slab's faces, 2 mm apart: the top (wound so its normal is +y) and the bottom (-y)
FACES = """NamedMaterial "{top}"
Shape "trianglemesh" "point3 P" [-20 {y_top} -20  -20 {y_top} 20  20 {y_top} 20  20 {y_top} -20]
    "integer indices" [0 1 2 0 2 3]
NamedMaterial "{bottom}"
Shape "trianglemesh" "point3 P" [-20 {y} -20  20 {y} 20  -20 {y} 20  -20 {y} -20  20 {y} -20  20 {y} 20]
    "integer indices" [0 1 2 3 4 5]
"""


def _faces(top: str, bottom: str, y: float = 1.0) -> str:
    return FACES.format(top=top, bottom=bottom, y=y, y_top=y + 0.002)


def _scene(tmp_path: Path, faces: str, depth: int = 1, radius: float = 0.0, slab: bool = True):
    text = SCENE.format(depth=depth, sun=" ".join(map(str, SUN)), radius=radius, film_eta=FILM_ETA,
                        film_nm=FILM_NM, eta=ETA, tint=" ".join(map(str, TINT)), slab=str(slab).lower(),
                        slab_shapes=faces)
    path = tmp_path / f"slab_{abs(hash(text))}.pbrt"
    path.write_text(text)
    return load_scene(path)


def _closed_form() -> np.ndarray:
    """T(θ) along the sun: the coating's T from air, the tint over the path inside, the bare face's
    1 − R (from air: the same T as from the glass side, by reciprocity)."""
    cos_t = SUN[1] / np.linalg.norm(SUN)
    coat = tmm_RT(cos_t, RGB3_NM, 1.0, FILM_ETA, ETA, FILM_NM)[1]
    bare = tmm_RT(cos_t, RGB3_NM, 1.0, ETA, ETA, 0.0)[1]
    cos_in = np.sqrt(1.0 - (1.0 - cos_t ** 2) / ETA ** 2)
    return coat * TINT ** (1.0 / cos_in) * bare


#: a cut-out sheet (alpha 0) between the plane and the slab: shadow rays step over it, then cross the slab
HOLE = """NamedMaterial "ground"
Shape "trianglemesh" "point3 P" [-20 0.5 -20  20 0.5 -20  20 0.5 20  -20 0.5 20] "integer indices" [0 1 2 0 2 3]
    "float alpha" 0
"""


@pytest.mark.parametrize("hole", [False, True], ids=["plain", "alpha"])
def test_flat_slab_shadow_matches_closed_form(tmp_path, hole):
    open_sky = render(_scene(tmp_path, ""), thin_film="rgb3")
    scene = _scene(tmp_path, _faces("coated", "bare") + (HOLE if hole else ""))
    features = upload(scene, "cpu", 8, 8).features
    assert features.thin_slabs and features.alpha == hole
    shadow = render(scene, thin_film="rgb3")
    T = shadow / open_sky
    expected = _closed_form()
    assert 0.1 < expected.mean() < 0.5                  # a tinted lens: neither clear nor black
    assert np.allclose(T, expected, rtol=2e-4, atol=0), (T.reshape(-1, 3).mean(0), expected)


def test_opaque_shadow_and_unmarked_lens_stay_black(tmp_path):
    lens = _faces("coated", "bare")
    # an opaque slab under the lens: its shadow is black whatever the lens passes
    opaque = lens + _faces("opaque", "opaque", y=0.8)
    img = render(_scene(tmp_path, opaque), thin_film="rgb3")
    assert np.all(img == 0.0)
    unmarked = _scene(tmp_path, lens, slab=False)
    assert not upload(unmarked, "cpu", 8, 8).features.thin_slabs
    assert np.all(render(unmarked, thin_film="rgb3") == 0.0)   # pbrt's behaviour: glass blocks shadow rays


@pytest.mark.parametrize("seed", [3])
def test_light_sampling_and_bsdf_sampling_agree_through_the_slab(tmp_path, seed):
    """A 10° sun: with MIS, the shadow ray's T and the BSDF path refracting through the faces share
    the light; BSDF sampling alone (no next-event estimation) is the reference. The BSDF path spends
    two bounces crossing the faces, the shadow ray none: at depth 5 the paths that only the shadow
    ray reaches within the depth (the plane seen twice in the slab's underside) carry ~0.1 %."""
    scene = _scene(tmp_path, _faces("coated", "bare"), depth=5, radius=10.0)
    mis = render(scene, spp=256, seed=seed, thin_film="rgb3").reshape(-1, 3).mean(0)
    bsdf = render(scene, spp=8192, seed=seed, thin_film="rgb3", nee=False).reshape(-1, 3)
    mean, err = bsdf.mean(0), bsdf.std(0) / np.sqrt(len(bsdf))   # pixels as independent estimates
    assert np.all(np.abs(mis - mean) < 4.0 * err + 0.01 * mean), (mis, mean, err)
    assert np.all(err < 0.03 * mean)                    # the reference resolves a double count (2x)


def test_thin_slab_faces_are_checked_where_the_scene_says_so(tmp_path):
    """A thin slab's face must be smooth clear glass, and shadow rays read a shape's own material,
    so a mix of a face is refused (both naming the file and line)."""
    from renderer.errors import SceneError, UnsupportedError

    bad = SCENE.replace('"bool thinslab" {slab}\nMakeNamedMaterial "bare"', '"bool thinslab" {slab} "float roughness" 0.1\n'
                        'MakeNamedMaterial "bare"')
    path = tmp_path / "rough.pbrt"
    path.write_text(bad.format(depth=1, sun="0 1 0", radius=0, film_eta=FILM_ETA, film_nm=FILM_NM, eta=ETA,
                               tint="0.5 0.5 0.5", slab="true", slab_shapes=""))
    with pytest.raises(SceneError, match=r"rough\.pbrt:\d+.*thinslab"):
        load_scene(path)
    mixed = _faces("coated", "bare") + ('MakeNamedMaterial "half" "string type" "mix" '
                                        '"string materials" ["coated" "ground"]\nNamedMaterial "half"\n'
                                        'Shape "sphere" "float radius" 0.1\n')
    with pytest.raises(UnsupportedError, match="thinslab"):
        upload(_scene(tmp_path, mixed), "cpu", 8, 8)
