"""pbrt-v4's procedural and combined textures against pbrt-v4's own images (see pbrt_compare):
fbm, wrinkled, windy, marble and dots (texture_noise.pbrt), the 3D checkerboard, a checkerboard of
textures and mixes of mixes (texture_nested.pbrt). Each also fails when a detail pbrt depends on
is changed."""
from __future__ import annotations

import numpy as np

from pbrt_compare import DISTINCT, assert_matches_pbrt, variant_chi
from renderer.scene.texture_params import STACK_DEPTH
from renderer.textures import noise, table


def test_the_permutation_is_pbrts_and_noise_vanishes_on_the_lattice():
    perm = noise.permutation()
    assert perm.shape == (512,) and sorted(perm[:256]) == list(range(256)) and (perm[:256] == perm[256:]).all()
    assert perm[:6].tolist() == [151, 160, 137, 91, 90, 15]         # Perlin's own table, as pbrt-v4 ships it


def test_noise_textures_match_pbrt(tmp_path, monkeypatch):
    """The image matches; with dots' inside and outside swapped back to what their names say
    (pbrt-v4 swaps them), or with another permutation table, it does not."""
    ref, ref_var = assert_matches_pbrt("texture_noise")
    swapped = [('"rgb inside" [0.8 0.25 0.2] "rgb outside" [0.2 0.3 0.8]',
                '"rgb inside" [0.2 0.3 0.8] "rgb outside" [0.8 0.25 0.2]')]
    assert variant_chi("texture_noise", swapped, ref, ref_var, tmp_path) > DISTINCT
    shuffled = np.random.default_rng(3).permutation(256).astype(np.int32)
    monkeypatch.setattr(table, "permutation", lambda: np.concatenate([shuffled, shuffled]))
    assert variant_chi("texture_noise", [], ref, ref_var, tmp_path) > DISTINCT


def test_3d_checkerboard_textured_checkerboard_and_mixes_of_mixes_match_pbrt(tmp_path):
    """texture_nested.pbrt nests up to 4 values deep (checkerboard of a mix and a 3D checkerboard;
    scale of a directionmix of a mix of mixes), under STACK_DEPTH; the 3D checkerboard made 2D
    (of the surface's uv) no longer matches."""
    assert STACK_DEPTH >= 4
    ref, ref_var = assert_matches_pbrt("texture_nested")
    flat = [('"checkerboard" "integer dimension" 3 "rgb', '"checkerboard" "integer dimension" 2 "rgb')]
    assert variant_chi("texture_nested", flat, ref, ref_var, tmp_path, ("grey_pattern.png",)) > DISTINCT
