"""The ``thinfilm`` material: lobes consistent with the optics, energy, furnaces, the bare-interface
limit, robustness over extreme parameters, both colour modes end to end, the thickness map."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import warp as wp

import renderer
from bsdf_harness import bsdf_moments, constant_rows
from renderer import optics
from renderer.color import spectral
from renderer.color.rgb_weights import make_rgb_weight_table
from renderer.api import init_warp
from renderer.settings import thin_film_samples
from renderer.cli import main as cli_main
from renderer.errors import RenderError, SceneError
from renderer.materials import dielectric, material, thinfilm
from renderer.materials.bsdf import BSDF, SPECULAR, Slots
from renderer.color.rgb_weights import RgbWeightTable
from renderer.parameters import TextureRef
from renderer.scene.description import MaterialDesc, MeshDesc, SceneDescription, TextureDesc
from scenes_py import HERE, params, single_object_scene

init_warp()

RGB3 = np.array(spectral.RGB3_WAVELENGTHS_NM)
MINI_SCENE = Path(__file__).parents[1] / "data" / "scenes" / "mini.pbrt"


def film(eta_outer=1.0, eta_film=1.33, eta_inner=1.5, k_inner=0.0, thickness=400.0, thicknessmap=0.0,
         thicknessscale=1.0, transmission=True, reflectance=0.0) -> dict:
    """thinfilm parameter values (a clear substrate has no reflectance to give)."""
    v = dict(eta_outer=eta_outer, eta_film=eta_film, eta_inner=eta_inner, k_inner=k_inner, thickness=thickness,
             thicknessmap=thicknessmap, thicknessscale=thicknessscale, transmission=transmission)
    return v if transmission else v | {"reflectance": reflectance}


def film_rows(cases: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """Slot rows (n, MAX_SLOTS, 3) and flags (n,) of thinfilm cases, as the upload lays them out."""
    laid = [constant_rows("thinfilm", c) for c in cases]
    return np.stack([r for r, _ in laid]), np.array([f for _, f in laid], dtype=np.int32)


@wp.kernel
def _probe(p: wp.array(dtype=Slots), flags: wp.array(dtype=int), wo: wp.array(dtype=wp.vec3),
           u: wp.array(dtype=wp.vec3), table: RgbWeightTable, n_lambda: int, film: wp.array(dtype=wp.vec3, ndim=2),
           sampled: wp.array(dtype=wp.vec3, ndim=2), dielectric_sampled: wp.array(dtype=wp.vec3, ndim=2)):
    """Per case: the film's (R, T) and the substrate lobe's f, pdf; thinfilm's sample (wi, weight,
    (pdf, eta, specular)) and, for comparison, a smooth dielectric of eta_inner / eta_outer given the same u."""
    i = wp.tid()
    b = BSDF()
    b.kind = 0
    b.p = p[i]
    b.flags = flags[i]
    b.wavelength_u = u[i][0]
    b.spectral = table
    b.spectral_n = n_lambda
    r, t = thinfilm.film_reflect_transmit(b, wo[i])
    film[i, 0] = r
    film[i, 1] = t
    wi = wp.normalize(wp.vec3(-wo[i][1], wo[i][0], wo[i][2]) + wp.vec3(0.1, 0.2, 0.3))
    e = thinfilm.eval_pdf(b, wo[i], wi)
    film[i, 2] = e.f
    film[i, 3] = wp.vec3(e.pdf, 0.0, 0.0)
    s = thinfilm.sample(b, wo[i], u[i])
    sampled[i, 0] = s.wi
    sampled[i, 1] = s.weight
    sampled[i, 2] = wp.vec3(s.pdf, s.eta, wp.where((s.flags & SPECULAR) != 0, 1.0, 0.0))
    eta = Slots()
    n_in = b.p[wp.static(thinfilm.SLOT.eta_inner), 0]
    eta[wp.static(dielectric.SLOT.eta), 0] = n_in / b.p[wp.static(thinfilm.SLOT.eta_outer), 0]
    d = BSDF()
    d.p = eta
    ds = dielectric.sample(d, wo[i], u[i])
    dielectric_sampled[i, 0] = ds.wi
    dielectric_sampled[i, 1] = ds.weight
    dielectric_sampled[i, 2] = wp.vec3(ds.pdf, ds.eta, 0.0)


def probe(cases: list[dict], wo: np.ndarray, u: np.ndarray, mode: str = "rgb3") -> dict[str, np.ndarray]:
    """Run :func:`_probe` over thinfilm cases (parameter values), wo and u (n, 3)."""
    rows, flags = film_rows(cases)
    n = len(rows)
    n_lambda = thin_film_samples(mode)
    table = make_rgb_weight_table("cpu")
    arrays = [wp.zeros((n, k), dtype=wp.vec3, device="cpu") for k in (4, 3, 3)]
    wp.launch(_probe, dim=n, inputs=[wp.array(rows, dtype=Slots, device="cpu"),
                                     wp.array(flags, dtype=int, device="cpu"),
                                     wp.array(wo.astype(np.float32), dtype=wp.vec3, device="cpu"),
                                     wp.array(u.astype(np.float32), dtype=wp.vec3, device="cpu"),
                                     table, n_lambda, *arrays], device="cpu")
    film, s, d = (a.numpy() for a in arrays)
    return {"R": film[:, 0], "T": film[:, 1], "f": film[:, 2], "pdf": film[:, 3, 0], "wi": s[:, 0],
            "weight": s[:, 1], "s_pdf": s[:, 2, 0], "eta": s[:, 2, 1], "specular": s[:, 2, 2],
            "d_wi": d[:, 0], "d_weight": d[:, 1], "d_pdf": d[:, 2, 0], "d_eta": d[:, 2, 1]}


def unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# ---------------------------------------------------------------------------------------------
# The BSDF against the optics


ANGLES = [(0.3, 0.2, 0.9), (0.9, 0.1, 0.1), (0.0, 0.0, 1.0), (0.5, -0.4, -0.6)]


@pytest.mark.parametrize("wo", ANGLES, ids=["oblique", "grazing", "normal", "below"])
@pytest.mark.parametrize("case", [dict(), dict(eta_film=1.55, eta_inner=1.66, thickness=500.0, transmission=False),
                                  dict(transmission=False, reflectance=0.8),
                                  dict(eta_film=2.4, eta_inner=1.0, k_inner=3.0, transmission=False)],
                         ids=["soap-on-glass", "seed-coat", "diffuse-base", "metal"])
def test_lobes_match_the_optics(case, wo):
    """E[sample weight] = R + T/eta'^2 (delta lobes) + the substrate's albedo (uniform estimate),
    with R and T from the optics at the seed's three wavelengths; sample/pdf/eval agree."""
    v = film(**case)
    m = bsdf_moments("thinfilm", v, wo, n=200_000)
    w = unit(wo)
    outer, inner = v["eta_outer"], complex(v["eta_inner"], v["k_inner"])
    transmissive = v["transmission"]
    if transmissive and w[2] < 0:
        outer, inner = v["eta_inner"], v["eta_outer"]
    R, T = optics.thin_film_reflectance_transmittance(abs(w[2]), RGB3, outer, v["eta_film"], inner, v["thickness"])
    eta_p = inner.real / outer if transmissive else 1.0
    specular = R + (T / eta_p ** 2 if transmissive else 0.0)
    tol = 5 * m["albedo_uniform_stderr"] + 0.01
    np.testing.assert_array_less(np.abs(m["albedo_sampled"] - m["albedo_uniform"] - specular), tol)
    assert m["max_inconsistency"] < 2e-3
    assert m["pdf_integral"] <= 1.0 + 0.02
    # reflected + diffusely returned energy never exceeds what arrived
    assert np.all(R + m["albedo_uniform"] <= 1.0 + tol)


def test_delta_lobes_have_no_density():
    m = bsdf_moments("thinfilm", film(), (0.3, 0.2, 0.9), n=20_000)
    assert m["pdf_integral"] == 0.0 and np.all(m["albedo_uniform"] == 0.0)


@pytest.mark.parametrize("mode", ["rgb3", "spectral:32"])
def test_lossless_film_reflects_plus_transmits_one(mode):
    """R + T = 1 per channel for lossless media, from either side, including past the critical
    angle from inside (T = 0); in spectral mode each evaluation is 1 up to the jittered white's
    error and exactly 1 on average."""
    rng = np.random.default_rng(2)
    n = 4000
    wo = unit(rng.normal(size=(n, 3)))
    cases = [film(eta_film=f, eta_inner=g, thickness=d)
             for f, g, d in zip(rng.uniform(1.0, 2.5, n), rng.uniform(1.0, 2.0, n), rng.uniform(0, 3000, n))]
    out = probe(cases, wo, rng.random((n, 3)), mode)
    total = out["R"] + out["T"]
    if mode == "rgb3":
        np.testing.assert_allclose(total, 1.0, atol=2e-5)
    else:
        np.testing.assert_allclose(total, 1.0, atol=1e-2)
        np.testing.assert_allclose(total.mean(axis=0), 1.0, atol=1e-3)
    inside = (wo[:, 2] < 0) & (np.hypot(wo[:, 0], wo[:, 1]) * np.array([c["eta_inner"] for c in cases]) > 1.0)
    assert inside.any() and np.all(out["T"][inside] < 1e-6)   # only the optics' 1e-12 regulariser leaks


def test_zero_thickness_is_the_bare_interface():
    """With no film the material makes the same choices, directions and weights as a smooth
    dielectric of eta_inner / eta_outer, whatever the film's index, from both sides."""
    rng = np.random.default_rng(3)
    n = 2000
    wo = unit(rng.normal(size=(n, 3)))
    cases = [film(eta_outer=o, eta_film=f, eta_inner=i, thickness=0.0)
             for o, f, i in zip(rng.uniform(1.0, 1.4, n), rng.uniform(1.0, 3.0, n), rng.uniform(1.3, 2.0, n))]
    u = rng.random((n, 3))
    out = probe(cases, wo, u)
    ok = out["d_pdf"] > 0
    away = np.abs(u[:, 2] - out["d_pdf"]) > 1e-4   # not on the reflect/refract boundary
    sel = ok & away
    assert sel.sum() > 0.9 * n
    np.testing.assert_allclose(out["wi"][sel], out["d_wi"][sel], atol=1e-5)
    np.testing.assert_allclose(out["weight"][sel], out["d_weight"][sel], rtol=1e-4)
    np.testing.assert_allclose(out["eta"][sel], out["d_eta"][sel], rtol=1e-6)


@pytest.mark.parametrize("mode", ["rgb3", "spectral:16"])
def test_no_nan_or_inf_over_extreme_parameters(mode):
    """Thickness 0 and 100 µm, indices 1..4, metal substrates, grazing and exactly tangent
    directions, both sides: every output finite, R and T in [0, 1], weights non-negative."""
    grid = []
    for outer in (1.0, 4.0):
        for layer in (1.0, 2.2, 4.0):
            for inner, k in ((1.0, 0.0), (4.0, 0.0), (0.2, 3.9)):
                for d in (0.0, 1e-3, 500.0, 1e5):
                    for trans in (False, True):
                        if trans and k > 0:
                            continue
                        grid.append(film(outer, layer, inner, k, d, 0.0, 1.0, trans, 0.5))
    dirs = unit([(1, 0, 1e-7), (1, 0, 0), (1, 0, -1e-7), (0.6, 0.0, 0.8), (0.6, 0.0, -0.8), (0, 0, 1), (0, 0, -1)])
    cases = [c for c in grid for _ in dirs]
    wo = np.tile(dirs, (len(grid), 1))
    out = probe(cases, wo, np.random.default_rng(4).random((len(cases), 3)), mode)
    for key in ("R", "T", "f", "pdf", "wi", "weight", "s_pdf"):
        assert np.all(np.isfinite(out[key])), key
    assert np.all((out["R"] >= 0) & (out["R"] <= 1) & (out["T"] >= 0) & (out["T"] <= 1))
    assert np.all(out["weight"] >= 0) and np.all(out["f"] >= 0)


def test_transmission_needs_a_clear_substrate():
    """Refused where the material is made, before anything is uploaded."""
    with pytest.raises(SceneError, match="clear substrate"):
        material("thinfilm", transmission=True, k_inner=2.0)
    with pytest.raises(SceneError, match="clear substrate"):
        material("thinfilm", transmission=True, reflectance=0.5)


# ---------------------------------------------------------------------------------------------
# End to end


@pytest.mark.parametrize("mode,thickness", [("rgb3", 0.0), ("rgb3", 400.0), ("spectral:32", 400.0)])
def test_furnace_film_coated_glass_sphere(mode, thickness):
    """A lossless coated sphere under a uniform sky of 1 renders 1: exactly without a film (the
    weights are grey), on average with one (the weights are coloured, the sum is not)."""
    desc = single_object_scene(material("thinfilm", eta_film=1.33, eta_inner=1.5, thickness=thickness,
                                        transmission=True))
    desc.integrator.max_depth = 64
    img = renderer.render(desc, spp=64, thin_film=mode)[4:12, 4:12]   # pixels that all see the sphere
    assert np.all(np.isfinite(img))
    if thickness == 0.0:
        np.testing.assert_allclose(img, 1.0, atol=1e-5)
    else:
        np.testing.assert_allclose(img.mean(axis=(0, 1)), 1.0, atol=0.01)


def test_furnace_coated_glass_sphere_at_few_wavelengths():
    """Few jittered wavelengths estimate white badly; under total internal reflection inside the
    glass R ≡ 1 was clipped at every bounce (0.926, 0.981, 0.914 at spectral:8). Balanced by the
    same jitter's white (coating.py), the furnace is 1 in every channel."""
    desc = single_object_scene(material("thinfilm", eta_film=1.33, eta_inner=1.5, thickness=400.0, transmission=True))
    desc.integrator.max_depth = 64
    img = renderer.render(desc, spp=64, thin_film="spectral:8")[4:12, 4:12]
    np.testing.assert_allclose(img.mean(axis=(0, 1)), 1.0, atol=0.005)


def quad_scene(material: MaterialDesc, fov: float) -> SceneDescription:
    """A unit-uv square filling the view head-on, under a uniform sky of 1: a pixel shows R."""
    quad = MeshDesc(positions=np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32),
                    indices=np.array([[0, 1, 2], [0, 2, 3]], np.int32),
                    uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32))
    return single_object_scene(material, mesh=quad, fov=fov)


def test_colour_modes_end_to_end():
    """At normal incidence over a white sky a coated black substrate shows the film's R: the
    seed's three wavelengths exactly in rgb3, the CIE integral in spectral mode (converged over
    samples), and the two differ by the seed's error."""
    desc = quad_scene(material("thinfilm", eta_film=1.55, eta_inner=1.66, thickness=500.0), fov=1.0)
    rgb3 = renderer.render(desc, spp=4, thin_film="rgb3").mean(axis=(0, 1))
    spectral = renderer.render(desc, spp=64, thin_film="spectral:32").mean(axis=(0, 1))
    expect_rgb3 = optics.thin_film_rgb(1.0, 1.0, 1.55, 1.66, 500.0, mode="rgb3")
    reference = optics.thin_film_rgb(1.0, 1.0, 1.55, 1.66, 500.0, mode="reference")
    np.testing.assert_allclose(rgb3, expect_rgb3, atol=1e-4)
    np.testing.assert_allclose(spectral, np.clip(reference, 0, 1), atol=3e-3)
    assert np.max(np.abs(rgb3 - spectral) / spectral) > 0.1   # a 4 % reflectance, 10–40 % off


def test_thickness_map_changes_the_colour():
    """thickness + thicknessscale × thicknessmap: a constant map of 200 at scale 0.5 is a 600 nm
    film; a checkerboard map gives two colours."""
    def render(tex: TextureDesc, scale: float, fov: float) -> np.ndarray:
        desc = quad_scene(material("thinfilm", thickness=500.0, thicknessmap=TextureRef("t"), thicknessscale=scale),
                          fov=fov)
        desc.textures["t"] = tex
        return renderer.render(desc, spp=2, thin_film="rgb3")

    const = TextureDesc("t", "float", "constant", params(value=200.0), HERE.file, HERE)
    img = render(const, 0.5, 1.0)
    np.testing.assert_allclose(img.mean(axis=(0, 1)), optics.thin_film_rgb(1.0, 1.0, 1.55, 1.66, 600.0, mode="rgb3"),
                               atol=1e-4)
    checks = TextureDesc("t", "float", "checkerboard", params(tex1=250.0, tex2=0.0, uscale=4.0, vscale=4.0),
                         HERE.file, HERE)
    colours = np.unique(np.round(render(checks, 1.0, 20.0).reshape(-1, 3), 3), axis=0)
    assert len(colours) >= 2 and np.max(np.ptp(colours, axis=0) / colours.mean(axis=0)) > 0.3


def test_mode_option_is_validated(capsys):
    with pytest.raises(RenderError, match="thin-film mode"):
        renderer.api.settings_for(single_object_scene(material("diffuse")), thin_film="spectral:0")
    assert cli_main([str(MINI_SCENE), "--thin-film", "rgb4", "-o", "/dev/null.png"]) == 2
    assert "thin-film mode" in capsys.readouterr().err
