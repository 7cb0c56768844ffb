"""``thinfilm`` with ``layered`` true: the film or stack as the top interface of the layered random
walk over a Lambertian base. A lossless film over a white base conserves energy; its albedo and
its f match the interreflection series summed in closed form from the film's own R and T (above
and below); a 0 nm film is ``coateddiffuse``; the walk's samples agree with its f; reciprocity."""
from __future__ import annotations

import numpy as np
import pytest

import renderer
from bsdf_harness import bsdf_moments, mean_f, weighted_cells_pvalue
from renderer import optics
from renderer.api import init_warp
from renderer.color import spectral
from renderer.errors import SceneError
from renderer.materials import material
from renderer.materials.bsdf import DIFFUSE, GLOSSY, REFLECTION, SPECULAR
from scenes_py import single_object_scene

init_warp()

RGB3 = np.array(spectral.RGB3_WAVELENGTHS_NM)
DEEP = dict(layered=True, maxdepth=100)   # walks long enough that truncation does not bias the albedo
MU = (np.arange(4000) + 0.5) / 4000       # midpoints for the hemispherical averages


def stack_of(v: dict) -> tuple[list, list, list]:
    """(eta, k, thickness) of a case's coating as the optics wrappers take them: outer, layers, substrate."""
    if "layer_eta" in v:
        n = len(v["layer_eta"]) * v.get("repeat", 1)
        eta = list(np.tile(v["layer_eta"], v.get("repeat", 1)))
        k = list(np.broadcast_to(v.get("layer_k", [0.0]), (len(v["layer_eta"]),))) * v.get("repeat", 1)
        d = list(np.tile(v["layer_thickness"], v.get("repeat", 1)))
        assert len(eta) == n
    else:
        eta, k, d = [v.get("eta_film", 1.55)], [0.0], [v.get("thickness", 500.0)]
    n0, n2 = v.get("eta_outer", 1.0), v.get("eta_inner", 1.66)
    return [n0, *eta, n2], [0.0, *k, 0.0], d


def film_RT(v: dict, cos: np.ndarray, from_below: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(R, T), shape (len(cos), 3), at the rgb3 wavelengths, for light from above or from the substrate."""
    eta, k, d = stack_of(v)
    if from_below:
        eta, k, d = eta[::-1], k[::-1], d[::-1]
    c = np.asarray(cos, np.float64)[:, None]
    return optics.multilayer_reflectance_transmittance(c, RGB3[None, :], eta, k, d)


def closed_form(v: dict, rho: np.ndarray, cos_o: float) -> tuple[np.ndarray, np.ndarray]:
    """Directional albedo of a smooth coating over a Lambertian base of albedo rho with every
    interreflection, A = R(θo) + T(θo) ρ T̄_out / (1 − ρ R̄_int) (R̄_int, T̄_out: the cosine-weighted
    means of R and T seen from the substrate, total internal reflection included), and the
    constant of the diffuse f: f = T(θo) T_below(θ'i) ρ / (π η² (1 − ρ R̄_int))."""
    r_b, t_b = film_RT(v, MU, from_below=True)
    r_int = 2 * (r_b * MU[:, None]).mean(axis=0)
    t_out = 2 * (t_b * MU[:, None]).mean(axis=0)
    r_o, t_o = film_RT(v, np.array([cos_o]))
    albedo = r_o[0] + t_o[0] * rho * t_out / (1 - rho * r_int)
    return albedo, rho / (np.pi * (1 - rho * r_int))


CASES = {
    "soap film, coloured base": dict(eta_film=1.33, thickness=400.0, eta_inner=1.5, reflectance=(0.9, 0.6, 0.3)),
    "white base under a stack": dict(layer_eta=[2.4, 1.46], layer_thickness=[57.3, 94.2], repeat=2, eta_inner=1.52,
                                     reflectance=1.0),
    "absorbing layer": dict(layer_eta=[1.8], layer_k=[0.05], layer_thickness=[120.0], eta_inner=1.5,
                            reflectance=0.7),
    "under water": dict(eta_outer=1.33, eta_film=1.45, thickness=350.0, eta_inner=1.6, reflectance=0.5),
}


@pytest.mark.parametrize("cos_o", [1.0, 0.5, 0.12])
@pytest.mark.parametrize("name", list(CASES))
def test_albedo_matches_the_interreflection_series(name, cos_o):
    v = CASES[name]
    rho = np.broadcast_to(np.asarray(v["reflectance"], np.float64), (3,))
    wo = (np.sqrt(1 - cos_o ** 2), 0.0, cos_o)
    m = bsdf_moments("thinfilm", v | DEEP, wo, n=200_000)
    expected, _ = closed_form(v, rho, cos_o)
    np.testing.assert_allclose(m["albedo_sampled"], expected, atol=5 * m["albedo_sampled_stderr"].max() + 2e-3)
    if name == "white base under a stack":
        np.testing.assert_allclose(expected, 1.0, atol=1e-3)    # lossless: the furnace is exactly 1


@pytest.mark.parametrize("name", ["soap film, coloured base", "absorbing layer", "under water"])
def test_f_matches_the_interreflection_series_pointwise(name):
    v = CASES[name]
    rho = np.broadcast_to(np.asarray(v["reflectance"], np.float64), (3,))
    pairs = [((0.3, 0.2, 0.9), (-0.5, 0.4, 0.6)), ((0.8, 0.0, 0.3), (0.1, 0.2, 0.95)), ((0, 0, 1), (0.9, 0, 0.2))]
    mean, err = mean_f("thinfilm", v | DEEP, pairs, n=8000)
    _, const = closed_form(v, rho, 1.0)
    eta = v["eta_inner"] / v.get("eta_outer", 1.0)
    for (wo, wi), f, e in zip(pairs, mean, err):
        co = wo[2] / np.linalg.norm(wo)
        ci = wi[2] / np.linalg.norm(wi)
        ci_inside = np.sqrt(1 - (1 - ci ** 2) / eta ** 2)
        t_o = film_RT(v, np.array([co]))[1][0]
        t_i = film_RT(v, np.array([ci_inside]), from_below=True)[1][0]
        expected = t_o * t_i * const / eta ** 2
        np.testing.assert_allclose(f, expected, rtol=0.01, atol=5 * e.max())


LOSSLESS = [dict(eta_film=1.33, thickness=400.0, eta_inner=1.5, reflectance=1.0),
            dict(eta_film=1.33, thickness=400.0, eta_inner=1.5, reflectance=1.0, roughness=0.3),
            dict(layer_eta=[2.4, 1.46], layer_thickness=[57.3, 94.2], repeat=3, eta_inner=1.52, reflectance=1.0,
                 uroughness=0.05, vroughness=0.4)]
LOSSLESS_IDS = ["smooth film", "rough film", "rough anisotropic stack"]
WO = [(0.3, 0.2, 0.9), (0.9, 0.1, 0.12), (0.4, -0.3, -0.7)]


@pytest.mark.parametrize("values", LOSSLESS, ids=LOSSLESS_IDS)
@pytest.mark.parametrize("wo", WO, ids=["oblique", "grazing", "below"])
def test_furnace_and_samples_agree_with_f(values, wo):
    """A lossless film over a white base reflects at most what arrives (exactly all of it when
    smooth: rough single-scattering facets lose some), and the walk's non-delta sample weights
    integrate to the ∫ f |cos| of the f estimator."""
    m = bsdf_moments("thinfilm", values | DEEP, wo, n=200_000)
    stderr = m["albedo_sampled_stderr"]
    assert np.all(m["albedo_sampled"] <= 1.0 + 5 * stderr)
    if "roughness" not in values and "uroughness" not in values:
        np.testing.assert_allclose(m["albedo_sampled"], 1.0, atol=5 * stderr.max() + 1e-3)
    nonspec = m["albedo_sampled_nonspecular"]
    tol = 5 * (m["albedo_uniform_stderr"] + stderr) + 0.01 * np.abs(m["albedo_uniform"]) + 1e-3
    assert np.all(np.abs(nonspec - m["albedo_uniform"]) < tol), (nonspec, m["albedo_uniform"])
    assert 0.1 - 1e-3 <= m["pdf_integral"] <= 2.5


@pytest.mark.parametrize("values", LOSSLESS[1:], ids=LOSSLESS_IDS[1:])
def test_weighted_directions_follow_f_chi_square(values):
    assert weighted_cells_pvalue("thinfilm", values | DEEP | dict(reflectance=0.8), (0.3, 0.2, 0.9)) > 1e-4


@pytest.mark.parametrize("values", LOSSLESS[:2], ids=LOSSLESS_IDS[:2])
def test_reciprocity_in_expectation(values):
    pairs = [((0.3, 0.2, 0.9), (-0.6, 0.3, 0.5)), ((0.8, -0.1, 0.25), (0.1, 0.3, 0.9))]
    f, e = mean_f("thinfilm", values | DEEP, pairs, n=20_000)
    g, d = mean_f("thinfilm", values | DEEP, [(b, a) for a, b in pairs], n=20_000, seed=6)
    assert np.allclose(f, g, rtol=0.02, atol=5 * np.hypot(e, d).max()), (f, g)


@pytest.mark.parametrize("roughness", [0.0, 0.3])
def test_zero_thickness_is_coateddiffuse(roughness):
    """A 0 nm film is the bare interface: the walk is pbrt's coateddiffuse of the same index."""
    film = dict(thickness=0.0, eta_film=2.0, eta_inner=1.5, reflectance=(0.8, 0.5, 0.2), roughness=roughness)
    coat = dict(eta=1.5, thickness=0.0, reflectance=(0.8, 0.5, 0.2), roughness=roughness, maxdepth=100)
    a = bsdf_moments("thinfilm", film | DEEP, (0.3, 0.2, 0.9), n=200_000)
    b = bsdf_moments("coateddiffuse", coat, (0.3, 0.2, 0.9), n=200_000, seed=2)
    tol = 5 * np.hypot(a["albedo_sampled_stderr"], b["albedo_sampled_stderr"]).max() + 1e-3
    np.testing.assert_allclose(a["albedo_sampled"], b["albedo_sampled"], atol=tol)
    pairs = [((0.3, 0.2, 0.9), (-0.5, 0.4, 0.6)), ((0.8, 0.0, 0.3), (0.1, 0.2, 0.95))]
    f, e = mean_f("thinfilm", film | DEEP, pairs, n=8000)
    g, d = mean_f("coateddiffuse", coat, pairs, n=8000, seed=7)
    np.testing.assert_allclose(f, g, rtol=0.01, atol=5 * np.hypot(e, d).max())


def test_interreflections_brighten_a_white_base():
    """The one-pass lobe drops what the film reflects back down; the walk returns it, so over a
    white base it is brighter and reaches the furnace's 1."""
    v = dict(eta_film=1.33, thickness=400.0, eta_inner=1.5, reflectance=1.0)
    one_pass = bsdf_moments("thinfilm", v, (0.3, 0.2, 0.9), n=100_000)["albedo_sampled"]
    walk = bsdf_moments("thinfilm", v | DEEP, (0.3, 0.2, 0.9), n=100_000)["albedo_sampled"]
    assert np.all(walk > one_pass + 0.02) and np.all(one_pass < 0.97)


@pytest.mark.parametrize("values,flags", [
    ({}, {REFLECTION | SPECULAR, REFLECTION | DIFFUSE}),
    (dict(roughness=0.3), {REFLECTION | GLOSSY, REFLECTION | DIFFUSE}),
], ids=["smooth", "rough"])
def test_samples_carry_their_lobe_flags(values, flags):
    m = bsdf_moments("thinfilm", dict(reflectance=0.8, layered=True) | values, (0.3, 0.2, 0.9), n=20_000)
    assert m["lobe_flags"] == flags


@pytest.mark.parametrize("values,match", [
    (dict(layered=True, transmission=True), "excludes"),
    (dict(layered=True, k_inner=2.0), "excludes"),
    (dict(maxdepth=5), "layered"),
    (dict(nsamples=2), "layered"),
])
def test_layered_parameters_are_checked(values, match):
    with pytest.raises(SceneError, match=match):
        material("thinfilm", **values)


def test_furnace_render_of_a_film_coated_white_sphere():
    """End to end, both colour modes: a lossless smooth film over a white base under a uniform sky
    of 1 renders 1 in both (the walk balances the spectral estimates: coating.py)."""
    desc = single_object_scene(material("thinfilm", eta_film=1.33, thickness=400.0, eta_inner=1.5, reflectance=1.0,
                                        layered=True, maxdepth=100))
    desc.integrator.max_depth = 64
    for mode in ("rgb3", "spectral:16"):
        img = renderer.render(desc, spp=64, thin_film=mode)[4:12, 4:12]
        assert np.all(np.isfinite(img))
        np.testing.assert_allclose(img.mean(axis=(0, 1)), 1.0, atol=0.01)
