"""The thin-film mode ``table``: ``thinfilm`` coatings read a per-material table over the angle
baked from the 1 nm reference, end to end through the renderer: the reference colour without
wavelength noise, white furnaces for a clear coated sphere and a layered coat over a white base,
and textured coatings that fall back to spectral:N, with a warning, exactly as spectral:N renders."""
from __future__ import annotations

import numpy as np
import pytest

import renderer
from renderer import optics
from renderer.api import init_warp
from renderer.color.spectral import TABLE_FALLBACK_SAMPLES, parse_mode
from renderer.materials import material
from renderer.parameters import TextureRef
from renderer.scene.description import MeshDesc, TextureDesc
from renderer.session import RenderStats
from scenes_py import HERE, params, single_object_scene

init_warp()


def quad_scene(m):
    """A unit-uv square filling the view head-on, under a uniform sky of 1: a pixel shows R."""
    quad = MeshDesc(positions=np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32),
                    indices=np.array([[0, 1, 2], [0, 2, 3]], np.int32),
                    uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32))
    return single_object_scene(m, mesh=quad, fov=1.0)


def test_modes_parse():
    assert parse_mode("table") == ("table", TABLE_FALLBACK_SAMPLES)
    assert parse_mode("table:8") == ("table", 8)
    for bad in ("table:0", "table:x", "tables"):
        with pytest.raises(ValueError, match="table"):
            parse_mode(bad)


@pytest.mark.parametrize("values,expect", [
    (dict(eta_film=1.55, eta_inner=1.66, thickness=500.0),
     lambda: optics.thin_film_rgb(1.0, 1.0, 1.55, 1.66, 500.0, mode="reference")),
    (dict(layer_eta=[2.4, 1.46], layer_thickness=[57.3, 94.2], repeat=4, eta_inner=1.52),
     lambda: optics.multilayer_rgb(1.0, np.r_[1.0, np.resize([2.4, 1.46], 8), 1.52], np.zeros(10),
                                   np.resize([57.3, 94.2], 8), mode="reference")),
], ids=["film", "stack"])
def test_one_sample_shows_the_reference_colour(values, expect):
    """Head-on over a white sky a coated black substrate shows R at normal incidence: in table
    mode one sample per pixel is already the 1 nm reference (no wavelength noise)."""
    img = renderer.render(quad_scene(material("thinfilm", **values)), spp=1, thin_film="table")
    np.testing.assert_allclose(img.reshape(-1, 3), np.broadcast_to(np.clip(expect(), 0, 1), (img[..., 0].size, 3)),
                               atol=5e-4)


@pytest.mark.parametrize("values", [
    dict(eta_film=1.33, eta_inner=1.5, thickness=400.0, transmission=True),
    dict(layer_eta=[2.4, 1.46], layer_thickness=[57.3, 94.2], repeat=3, eta_inner=1.52, transmission=True),
    dict(eta_film=1.33, thickness=400.0, eta_inner=1.5, reflectance=1.0, layered=True, maxdepth=100),
], ids=["clear film", "clear stack", "layered over white"])
def test_white_furnace(values):
    """Lossless coatings under a uniform sky of 1 render 1: the table's R + T = 1 per channel at
    every angle, both sides of the clear substrate (total internal reflection inside included)."""
    desc = single_object_scene(material("thinfilm", **values))
    desc.integrator.max_depth = 64
    img = renderer.render(desc, spp=64, thin_film="table")[4:12, 4:12]
    assert np.all(np.isfinite(img))
    np.testing.assert_allclose(img.mean(axis=(0, 1)), 1.0, atol=0.01)


def test_a_textured_coating_falls_back_to_spectral_n_with_a_warning():
    """A checkerboard thickness map: no one table describes the coating, so table:8 renders it
    exactly as spectral:8 does (same samples, bit for bit) and says so."""
    desc = quad_scene(material("thinfilm", thickness=500.0, thicknessmap=TextureRef("t")))
    desc.textures["t"] = TextureDesc("t", "float", "checkerboard", params(tex1=250.0, tex2=0.0, uscale=4.0,
                                                                           vscale=4.0), HERE.file, HERE)
    stats = RenderStats()
    table = renderer.render(desc, spp=2, thin_film="table:8", stats=stats)
    assert any("thicknessmap" in w and "spectral:8" in w for w in stats.warnings)
    np.testing.assert_array_equal(table, renderer.render(desc, spp=2, thin_film="spectral:8"))
