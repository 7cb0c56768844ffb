"""``thinfilm`` with a multilayer stack: the BSDF's coating colour against the optics, one layer
against the single film, the periodic shorthand, seeded disorder, the thickness map, dispersion,
light from the substrate side, both colour modes, bad input, and a stack scene end to end."""
from __future__ import annotations

import numpy as np
import pytest
import warp as wp

import renderer
from bsdf_harness import bsdf_from_rows, constant_rows, layer_table
from renderer import optics
from renderer.api import init_warp
from renderer.color import spectral
from renderer.color.rgb_weights import RgbWeightTable, make_rgb_weight_table
from renderer.errors import SceneError
from renderer.materials import material, thinfilm
from renderer.materials.bsdf import Slots
from renderer.materials.stack import stack_rows

init_warp()

RGB3 = np.array(spectral.RGB3_WAVELENGTHS_NM)
TIO2_SIO2 = dict(layer_eta=[2.4, 1.46], layer_thickness=[57.3, 94.2], repeat=4, eta_inner=1.52)


@wp.kernel
def _coat(p: Slots, flags: int, layers: wp.array(dtype=wp.vec4), first: int, count: int, table: RgbWeightTable,
          n_lambda: int, u: float, w: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec3, ndim=2)):
    i = wp.tid()
    b = bsdf_from_rows(p, flags, 0, layers, first, count)
    b.spectral = table
    b.spectral_n = n_lambda
    b.wavelength_u = u
    r, t = thinfilm.film_reflect_transmit(b, w[i])
    out[i, 0] = r
    out[i, 1] = t


def coat(values: dict, cos_theta, mode: str = "rgb3", u: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """The BSDF's RGB (R, T) of the coating for light arriving at each cos θ (negative: from below)."""
    rows, flags = constant_rows("thinfilm", values)
    c = np.atleast_1d(np.asarray(cos_theta, np.float64))
    w = np.stack([np.sqrt(1 - c ** 2), np.zeros_like(c), c], -1).astype(np.float32)
    out = wp.zeros((len(c), 2), dtype=wp.vec3, device="cpu")
    n = 0 if mode == "rgb3" else int(mode.split(":")[1])
    wp.launch(_coat, dim=len(c), inputs=[Slots(*rows.ravel().tolist()), int(flags), *layer_table("thinfilm", values),
                                         make_rgb_weight_table("cpu"), n, float(u),
                                         wp.array(w, dtype=wp.vec3, device="cpu"), out], device="cpu")
    o = out.numpy()
    return o[:, 0], o[:, 1]


def stack_optics(eta_outer, rows: np.ndarray, eta_inner, k_inner, cos_theta, lam, scale: float = 1.0):
    eta = [eta_outer, *rows[:, 0], eta_inner]
    k = [0.0, *rows[:, 2], k_inner]
    return optics.multilayer_reflectance_transmittance(cos_theta, lam, eta, k, rows[:, 3] * scale, rows[:, 1])


COS = np.array([1.0, 0.8, 0.5, 0.2, 0.05])


def test_stack_colour_is_the_optics_at_rgb3():
    values = TIO2_SIO2 | dict(transmission=True)
    r, t = coat(values, COS)
    rows = stack_rows(material("thinfilm", **values).values)
    R, T = stack_optics(1.0, rows, 1.52, 0.0, COS[:, None], RGB3[None, :])
    np.testing.assert_allclose(r, R, atol=1e-6)
    np.testing.assert_allclose(t, T, atol=1e-6)
    np.testing.assert_allclose(r + t, 1.0, atol=1e-5)
    assert r[0, 1] > 0.9 > r[0, 0]   # the quarter-wave design (550 nm) mirrors green, not red


@pytest.mark.parametrize("mode", ["rgb3", "spectral:8"])
@pytest.mark.parametrize("transmission", [True, False])
def test_one_layer_stack_is_the_single_film(mode, transmission):
    film = dict(eta_film=1.55, thickness=420.0, eta_inner=1.66, transmission=transmission)
    stack = dict(layer_eta=[1.55], layer_thickness=[420.0], eta_inner=1.66, transmission=transmission)
    cos = np.r_[COS, -COS] if transmission else COS
    for u in (0.1, 0.7):
        for a, b in zip(coat(film, cos, mode, u), coat(stack, cos, mode, u)):
            np.testing.assert_allclose(a, b, atol=2e-6)


def test_repeat_is_the_unit_cell_written_out():
    short = stack_rows(material("thinfilm", layer_eta=[1.6, 1.43], layer_thickness=[400.0, 30.0], repeat=3).values)
    long = stack_rows(material("thinfilm", layer_eta=[1.6, 1.43] * 3, layer_thickness=[400.0, 30.0] * 3).values)
    np.testing.assert_array_equal(short, long)
    assert short.shape == (6, 4)


def test_disorder_is_seeded_and_relative():
    base = dict(layer_eta=[1.6, 1.43], layer_thickness=[400.0, 30.0], repeat=500)
    rows = stack_rows(material("thinfilm", **base, layer_disorder=[0.2, 0.0], seed=4).values)
    again = stack_rows(material("thinfilm", **base, layer_disorder=[0.2, 0.0], seed=4).values)
    other = stack_rows(material("thinfilm", **base, layer_disorder=[0.2, 0.0], seed=5).values)
    np.testing.assert_array_equal(rows, again)
    assert not np.array_equal(rows, other)
    platelets, matrix = rows[0::2, 3], rows[1::2, 3]
    np.testing.assert_array_equal(matrix, 30.0)
    assert platelets.mean() == pytest.approx(400.0, rel=0.03)
    assert platelets.std() / 400.0 == pytest.approx(0.2, rel=0.15)
    assert np.all(platelets >= 0.0)
    none = stack_rows(material("thinfilm", **base, layer_disorder=[0.0], seed=4).values)
    np.testing.assert_array_equal(none, stack_rows(material("thinfilm", **base).values))


def test_thickness_map_scales_the_whole_stack():
    """A map adds nanometres to the stack's total, spread over its layers in proportion."""
    values = TIO2_SIO2 | dict(transmission=True)
    total = material("thinfilm", **values).values["layer_thickness"]
    total = 4 * sum(total)
    r, t = coat(values | dict(thicknessmap=0.5 * total, thicknessscale=1.0), COS)
    rows = stack_rows(material("thinfilm", **values).values)
    R, T = stack_optics(1.0, rows, 1.52, 0.0, COS[:, None], RGB3[None, :], scale=1.5)
    np.testing.assert_allclose(r, R, atol=2e-6)
    np.testing.assert_allclose(t, T, atol=2e-6)


def test_cauchy_dispersion_per_layer():
    values = dict(layer_eta=[1.9, 1.45], layer_cauchyb=[0.04, 0.004], layer_thickness=[300.0, 500.0], eta_inner=1.5)
    r, _ = coat(values, COS)
    rows = stack_rows(material("thinfilm", **values).values)
    R, _ = stack_optics(1.0, rows, 1.5, 0.0, COS[:, None], RGB3[None, :])
    np.testing.assert_allclose(r, R, atol=1e-6)
    n_blue = 1.9 + 0.04 / 0.475 ** 2
    R_manual, _ = optics.multilayer_reflectance_transmittance(COS, 475.0, [1.0, n_blue, 1.45 + 0.004 / 0.475 ** 2,
                                                                            1.5], np.zeros(4), [300.0, 500.0])
    np.testing.assert_allclose(r[:, 2], R_manual, atol=1e-6)
    flat, _ = coat(values | dict(layer_cauchyb=[0.0]), COS)
    assert np.abs(flat - r).max() > 1e-2


def test_light_from_the_substrate_sees_the_stack_reversed():
    values = dict(layer_eta=[2.4, 1.46, 1.9], layer_k=[0.0, 0.0, 0.0], layer_thickness=[60.0, 90.0, 150.0],
                  eta_outer=1.0, eta_inner=1.52, transmission=True)
    cos = np.array([0.95, 0.7, 0.4])
    r, t = coat(values, -cos)
    rows = stack_rows(material("thinfilm", **values).values)[::-1]
    R, T = stack_optics(1.52, rows, 1.0, 0.0, cos[:, None], RGB3[None, :])
    np.testing.assert_allclose(r, R, atol=1e-6)
    np.testing.assert_allclose(t, T, atol=1e-6)
    np.testing.assert_allclose(r + t, 1.0, atol=1e-5)


def test_metal_stack_absorbs_and_stays_physical():
    values = dict(layer_eta=[2.5, 3.1, 2.5], layer_k=[0.05, 3.3, 0.05], layer_thickness=[40.0, 12.0, 40.0],
                  eta_inner=1.52, transmission=False, reflectance=0.5)
    for mode in ("rgb3", "spectral:16"):
        r, t = coat(values, np.r_[COS, -COS], mode)
        assert np.all(np.isfinite(r)) and np.all((r >= 0) & (r <= 1)) and np.all(t == 0.0)


@pytest.mark.parametrize("values,match", [
    (dict(layer_eta=[1.5], layer_thickness=[100.0], eta_film=1.4), "belong to one film"),
    (dict(layer_eta=[1.5], layer_thickness=[100.0], thickness=100.0), "belong to one film"),
    (dict(layer_eta=[1.5, 1.4]), "needs \"layer_thickness\""),
    (dict(layer_eta=[1.5, 1.4], layer_thickness=[1.0, 2.0, 3.0]), "needs 1 or 2 values"),
    (dict(layer_thickness=[100.0]), "needs \"layer_eta\""),
    (dict(layer_eta=[1.5, 1.4], layer_thickness=[1.0], repeat=1500), "more than"),
    (dict(layer_eta=[1.5], layer_thickness=[-1.0]), "outside"),
])
def test_bad_stacks_are_refused(values, match):
    with pytest.raises(SceneError, match=match):
        material("thinfilm", **values)


def test_stack_scene_renders_in_both_modes(tmp_path):
    scene = tmp_path / "stack.pbrt"
    scene.write_text('''LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [30]
Film "rgb" "integer xresolution" [16] "integer yresolution" [16] "string filename" ["s.exr"]
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Material "thinfilm" "float layer_eta" [2.4 1.46] "float layer_thickness" [57.3 94.2] "integer repeat" [5]
    "float layer_disorder" [0.05] "integer seed" [3] "float eta_inner" [1.52] "bool transmission" [true]
Shape "sphere" "float radius" [1]
''')
    desc = renderer.load_scene(scene)
    images = {m: renderer.render(desc, spp=4, device="cpu", seed=1, thin_film=m) for m in ("rgb3", "spectral:8")}
    for img in images.values():
        assert np.all(np.isfinite(img)) and img.mean() > 0.05
    # a lossless coated glass sphere in a white furnace stays white in either mode
    for img in images.values():
        assert abs(float(img.mean()) - 1.0) < 0.05


def test_stack_parameter_of_the_wrong_type_names_its_line(tmp_path):
    scene = tmp_path / "bad.pbrt"
    scene.write_text('WorldBegin\nMaterial "thinfilm" "float layer_eta" [1.5]\n'
                     '    "integer layer_thickness" [100]\nShape "sphere"\n')
    with pytest.raises(SceneError, match="layer_thickness") as info:
        renderer.load_scene(scene)
    assert info.value.loc is not None and info.value.loc.line in (2, 3)
