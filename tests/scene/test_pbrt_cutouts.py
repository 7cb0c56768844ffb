"""Shape alpha cut-outs, the mix material and the interface material against pbrt-v4's own images
(see pbrt_compare), and the rules they follow: alpha 0 is a hole and fractional alpha keeps a hit
with that probability, for camera and shadow rays (shape_alpha.pbrt); a mix shades each hit with
one whole material, chosen by a hash of the hit; an interface is invisible (material_mix.pbrt)."""
from __future__ import annotations

import numpy as np
import pytest
import warp as wp

from pbrt_compare import DATA, DISTINCT, assert_matches_pbrt, variant_chi
from renderer.api import load_scene
from renderer.device.runtime import init_warp
from renderer.device.scene import upload
from renderer.errors import SceneError, UnsupportedError
from renderer.geometry.intersect import Surface
from renderer.materials.selection import choose_material
from renderer.scene import load_description
from renderer.textures import TextureTable, Textures

HEAD = 'Camera "perspective"\nWorldBegin\nLightSource "infinite"\n'      # scene text after it starts at line 4


def write(tmp_path, text: str):
    path = tmp_path / "scene.pbrt"
    path.write_text(HEAD + text)
    return path


def test_alpha_cutouts_match_pbrt(tmp_path):
    """Holes (a 0/1 checkerboard), constant 0.4 and an image's fractional values, seen directly and
    in shadows; opaque shapes, or fractional alpha taken as opaque, no longer match."""
    ref, ref_var = assert_matches_pbrt("shape_alpha")
    opaque = [(' "texture alpha" "holes"', ""), (' "float alpha" 0.4', ""), (' "texture alpha" "grey"', "")]
    assert variant_chi("shape_alpha", opaque, ref, ref_var, tmp_path, ("grey_pattern.png",)) > DISTINCT
    rounded = [('"float alpha" 0.4', '"float alpha" 1')]
    assert variant_chi("shape_alpha", rounded, ref, ref_var, tmp_path, ("grey_pattern.png",)) > DISTINCT


def test_mix_and_interface_materials_match_pbrt(tmp_path):
    """Constant and textured amounts and a mix of mixes; every mix's two materials swapped (each
    amount then weights the other one), or the interface made a surface, no longer match."""
    ref, ref_var = assert_matches_pbrt("material_mix")
    swapped = [('["red" "metal"]', '["metal" "red"]'), ('["blue" "metal"]', '["metal" "blue"]'),
               ('["redmetal" "blue"]', '["blue" "redmetal"]')]
    assert variant_chi("material_mix", swapped, ref, ref_var, tmp_path, ("grey_pattern.png",)) > DISTINCT
    visible = [('Material "interface"', 'Material "diffuse"')]
    assert variant_chi("material_mix", visible, ref, ref_var, tmp_path, ("grey_pattern.png",)) > DISTINCT


def test_only_scenes_with_cutouts_or_mixes_get_those_kernels():
    plain = upload(load_scene(DATA / "texture_mix.pbrt"), "cpu").features
    assert not plain.alpha and not plain.mix
    mixed = upload(load_scene(DATA / "material_mix.pbrt"), "cpu").features
    assert mixed.alpha and mixed.mix                      # the interface sphere is an alpha-0 cut-out
    assert upload(load_scene(DATA / "shape_alpha.pbrt"), "cpu").features.alpha


@wp.kernel
def _choose(kind: wp.array(dtype=int), mix: wp.array(dtype=wp.vec3i), tex: Textures, points: wp.array(dtype=wp.vec3),
            dirs: wp.array(dtype=wp.vec3), out: wp.array(dtype=int)):
    i = wp.tid()
    s = Surface()
    s.p = points[i]
    s.ng = wp.vec3(0.0, 0.0, 1.0)
    out[i] = choose_material(kind, mix, tex, 2, s, dirs[i])


def test_a_mix_picks_one_whole_material_per_hit_with_the_amounts_probability():
    """Material 2 mixes materials 0 and 1 with amount 0.3: over 20000 random hits the second is
    chosen 30% of the time (binomial sigma 0.3%), and the same hit (point and direction) always
    gets the same material, as pbrt-v4's hash-based choice."""
    init_warp()
    table = TextureTable()
    amount = table.add_constant(0.3)
    tex, keep = table.upload("cpu")
    kind = wp.array(np.array([0, 0, -2], np.int32), dtype=int, device="cpu")
    mix = wp.array(np.array([[0, 0, 0], [0, 0, 0], [0, 1, amount]], np.int32), dtype=wp.vec3i, device="cpu")
    rng = np.random.default_rng(5)
    n = 20000
    p = rng.uniform(-3, 3, (n, 3)).astype(np.float32)
    d = rng.normal(size=(n, 3))
    d = (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)
    runs = []
    for _ in range(2):
        out = wp.zeros(n, dtype=int, device="cpu")
        wp.launch(_choose, dim=n, inputs=[kind, mix, tex, wp.array(p, dtype=wp.vec3, device="cpu"),
                                          wp.array(d, dtype=wp.vec3, device="cpu"), out], device="cpu")
        runs.append(out.numpy())
    assert set(np.unique(runs[0])) == {0, 1}
    assert abs(runs[0].mean() - 0.3) < 0.012
    assert np.array_equal(runs[0], runs[1])


@pytest.mark.parametrize("text, line, match", [
    ('MakeNamedMaterial "m" "string type" "mix" "string materials" ["a"]\n', 4, "exactly two named materials"),
    ('Material "mix" "string materials" ["a" "nope"]\nMakeNamedMaterial "a" "string type" "diffuse"\n'
     'Shape "sphere"\n', 4, 'no named material "nope"'),
    ('Shape "sphere" "texture alpha" "nope"\n', 4, 'alpha" names texture "nope"'),
    ('AreaLightSource "diffuse"\nShape "sphere" "float alpha" 0.5\n', 5, '"alpha" on an area light'),
])
def test_mix_and_alpha_errors_are_located(tmp_path, text, line, match):
    path = write(tmp_path, text)
    with pytest.raises(SceneError, match=match) as info:
        load_description(path)
    assert info.value.loc.line == line


def test_a_mix_of_the_interface_material_and_a_cycle_of_mixes_are_refused(tmp_path):
    for text, match in [('MakeNamedMaterial "i" "string type" "interface"\n'
                         'MakeNamedMaterial "d" "string type" "diffuse"\n', "a mix of the interface material"),
                        ('MakeNamedMaterial "i" "string type" "mix" "string materials" ["m" "m"]\n'
                         'MakeNamedMaterial "d" "string type" "diffuse"\n', "form a cycle")]:
        scene = load_scene(write(tmp_path, text + 'MakeNamedMaterial "m" "string type" "mix" '
                                                  '"string materials" ["d" "i"]\nNamedMaterial "m"\nShape "sphere"\n'))
        with pytest.raises(UnsupportedError, match=match):
            upload(scene, "cpu")


def test_an_area_light_on_an_interface_shape_is_ignored_with_a_warning_as_pbrt(tmp_path):
    path = write(tmp_path, 'AttributeBegin\nAreaLightSource "diffuse"\nMaterial "interface"\nShape "sphere"\n'
                           'AttributeEnd\nShape "disk"\n')
    s = load_description(path)
    assert s.shapes[0].area_light is None
    assert f'{path}:7: ignoring the area light of a shape with the "interface" material (as pbrt-v4 does)' in s.warnings
