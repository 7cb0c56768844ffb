"""A film on the boundary of pbrt-v4's ``subsurface`` material (renderer.materials.film_body):
a 0 nm film is the bare material to float rounding; over an absorbing body it is the film over an
absorber (``thinfilm``'s opaque substrate of the same index); its lobes sample what they evaluate;
its exit lobe hands over what the profile brings (eta², the bare lobe's energy); a flat body under
a white sky renders the closed form R + T ρ k T̄_coat / c (k: what the body returns of what the
film keeps in); a white body in a white furnace never
returns more than 1."""
from __future__ import annotations

import numpy as np
import pytest

import renderer
from bsdf_harness import bsdf_moments
from renderer import optics
from renderer.api import init_warp
from renderer.color import spectral
from renderer.materials import material
from renderer.materials.beam_diffusion import fresnel_dielectric
from renderer.materials.subsurface import exit_normalisation_host
from scenes_py import flat_body_scene, single_object_scene
from subsurface_lobes import LOBES as SUBSURFACE_LOBES

init_warp()
ETA = 1.33
RGB3 = np.array(spectral.RGB3_WAVELENGTHS_NM)
SOAP = dict(thickness=380.0, eta_film=1.45)
NACRE = dict(layer_eta=[1.68, 1.43], layer_thickness=[400.0, 25.0], repeat=4)
BALANCE_NODES = 16


def film_RT(film: dict, cos: np.ndarray, eta: float = ETA) -> tuple[np.ndarray, np.ndarray]:
    """(R, T) (len(cos), 3) at the rgb3 wavelengths from outside: vacuum | film or stack | eta."""
    if "layer_eta" in film:
        layers = list(np.tile(film["layer_eta"], film.get("repeat", 1)))
        d = list(np.tile(film["layer_thickness"], film.get("repeat", 1)))
    else:
        layers, d = [film["eta_film"]], [film["thickness"]]
    c = np.asarray(cos, np.float64)[:, None]
    return optics.multilayer_reflectance_transmittance(c, RGB3[None, :], [1.0, *layers, eta],
                                                       [0.0] * (len(layers) + 2), d)


def balance(film: dict, rho_eff: np.ndarray) -> np.ndarray:
    """The exit balance k = (1 − a R̄_bare) / (1 − a R̄_coat) (renderer.materials.film_body), with the
    device's midpoint rule in μ²: R̄ = 1 − T̄/eta², a = rho_eff / (T̄_bare/eta² + rho_eff R̄_bare)."""
    mu = np.sqrt((np.arange(BALANCE_NODES) + 0.5) / BALANCE_NODES)
    t_bare = (1 - fresnel_dielectric(mu, ETA)).mean() / ETA ** 2
    t_coat = film_RT(film, mu)[1].mean(axis=0) / ETA ** 2
    a = rho_eff / (t_bare + rho_eff * (1 - t_bare))
    return (1 - a * (1 - t_bare)) / (1 - a * (1 - t_coat))


LOBES = {**SUBSURFACE_LOBES, "whole": None}


@pytest.mark.parametrize("lobe", ["exit", "surface", "whole"])
@pytest.mark.parametrize("film", [SOAP, NACRE], ids=["soap", "nacre"])
def test_coated_lobes_sample_what_they_evaluate(lobe, film):
    """Rough (0.3) coated boundary: sample() reports eval_pdf()'s value and density, importance and
    uniform sampling agree; the exit lobe's albedo is eta² T̄_coat / c per channel (T̄ = 2∫T μ dμ
    of the host transfer-matrix film); the reflection alone is the film's R (below 1)."""
    params = dict(reflectance=(0.5, 0.5, 0.5), roughness=0.3, **film)
    m = bsdf_moments("subsurface", params, (0.3, 0.2, 0.9), n=200_000, funcs=LOBES[lobe])
    assert m["max_inconsistency"] < 2e-3
    tol = 5 * m["albedo_uniform_stderr"] + 1e-3
    assert np.all(np.abs(m["albedo_sampled"] - m["albedo_uniform"]) < tol), m
    if lobe == "exit":
        assert abs(m["pdf_integral"] - 1.0) < 0.01
        mu = (np.arange(20000) + 0.5) / 20000
        t_bar = 2 * (film_RT(film, mu)[1] * mu[:, None]).mean(axis=0)
        c = exit_normalisation_host(ETA)
        np.testing.assert_allclose(m["albedo_sampled"], ETA ** 2 * t_bar / c, rtol=3e-3)
    elif lobe == "surface":
        assert 0.5 < m["pdf_integral"] <= 1.0 + 0.01
        assert np.all(m["albedo_sampled"] < 1.0)
    else:
        assert np.all(m["albedo_sampled"] <= 1.0 / 1.0 + 5 * m["albedo_sampled_stderr"] + 1e-3)


def test_zero_thickness_is_the_bare_boundary():
    """Every lobe of a 0 nm film (smooth and rough, spectral:32: a flat spectrum, balanced) equals
    the bare dielectric's to float rounding, and so does a flat body's image."""
    wo = (0.3, 0.2, 0.9)
    for rough in (0.0, 0.3):
        for lobe in ("exit", "surface", "whole"):
            bare = bsdf_moments("subsurface", dict(roughness=rough), wo, n=20_000, funcs=LOBES[lobe])
            film = bsdf_moments("subsurface", dict(roughness=rough, thickness=0.0, eta_film=1.6), wo, n=20_000,
                                funcs=LOBES[lobe])
            for key in ("albedo_uniform", "albedo_sampled", "pdf_integral"):
                np.testing.assert_allclose(film[key], bare[key], rtol=1e-5, atol=1e-7, err_msg=f"{rough} {lobe} {key}")
    bare = material("subsurface", reflectance=(0.8, 0.5, 0.3), mfp=(0.3, 0.2, 0.1), roughness=0.2)
    zero = material("subsurface", reflectance=(0.8, 0.5, 0.3), mfp=(0.3, 0.2, 0.1), roughness=0.2, thickness=0.0,
                    eta_film=1.6)
    images = [renderer.render(_volpath(single_object_scene(m, res=8)), spp=64, seed=5) for m in (bare, zero)]
    np.testing.assert_allclose(images[1], images[0], rtol=1e-4, atol=1e-5)


def _volpath(desc):
    desc.integrator.kind = "volpath"
    desc.integrator.max_depth = 6
    return desc


def test_absorbing_body_is_the_film_over_an_absorber():
    """A body that absorbs everything it takes in (sigma_s 0): the coated subsurface material is the
    film over an absorber of the same index, which ``thinfilm`` renders with its opaque substrate
    (reflectance 0, no compensation); a rough sphere under a white sky, the same image within noise."""
    film = dict(layer_eta=[1.68, 1.43], layer_thickness=[400.0, 25.0], repeat=3)
    body = material("subsurface", sigma_a=(50.0, 50.0, 50.0), sigma_s=(0.0, 0.0, 0.0), eta=1.5, roughness=0.2, **film)
    absorber = material("thinfilm", eta_inner=1.5, roughness=0.2, multiscatter=False, **film)
    a, b = (renderer.render(_volpath(single_object_scene(m, res=12)), spp=256, seed=s, thin_film="rgb3")
            .reshape(-1, 3) for m, s in ((body, 1), (absorber, 2)))
    d = a - b
    se = d.std(0) / np.sqrt(len(d))
    assert np.all(np.abs(d.mean(0)) < 4 * se + 2e-3), (a.mean(0), b.mean(0), se)
    assert np.all(a.mean(0) > 0.02)          # the film reflects visibly


@pytest.mark.parametrize("film", [SOAP, NACRE], ids=["soap", "nacre"])
def test_flat_coated_body_under_white_sky(tmp_path, film):
    """A smooth flat coated body seen from above under a white sky (rgb3): the film's mirror
    reflection R(0°) plus what enters, T(0°), spread by the profile (its integral: the reflectance)
    and let out by the coated exit lobe with its balance: L = R + T ρ k T̄_coat / c. Also the
    balance's limits: a white body lets out all the film traps (k T̄_coat = T̄_bare), a black one
    none of it (k = 1)."""
    refl = np.array([0.9, 0.5, 0.2])
    if "layer_eta" in film:
        text = (f'"float layer_eta" [{" ".join(map(str, film["layer_eta"]))}] "float layer_thickness" '
                f'[{" ".join(map(str, film["layer_thickness"]))}] "integer repeat" [{film["repeat"]}]')
    else:
        text = f'"float thickness" [{film["thickness"]}] "float eta_film" [{film["eta_film"]}]'
    body = f'"rgb reflectance" [{refl[0]} {refl[1]} {refl[2]}] "rgb mfp" [0.2 0.1 0.05] {text}'
    (tmp_path / "flat.pbrt").write_text(flat_body_scene("subsurface", body))
    scene = renderer.load_scene(tmp_path / "flat.pbrt")
    img = renderer.render(scene, spp=1024, seed=3, thin_film="rgb3").reshape(-1, 3)
    r0, t0 = (x[0] for x in film_RT(film, np.array([1.0])))
    mu = (np.arange(20000) + 0.5) / 20000
    t_bar = 2 * (film_RT(film, mu)[1] * mu[:, None]).mean(axis=0)
    expected = r0 + t0 * refl * t_bar * balance(film, refl) / exit_normalisation_host(ETA)
    mu16 = np.sqrt((np.arange(BALANCE_NODES) + 0.5) / BALANCE_NODES)
    np.testing.assert_allclose(balance(film, np.ones(3)) * film_RT(film, mu16)[1].mean(axis=0),
                               (1 - fresnel_dielectric(mu16, ETA)).mean(), rtol=1e-6)
    np.testing.assert_allclose(balance(film, np.zeros(3)), 1.0)
    stderr = img.std(0) / np.sqrt(len(img))
    assert np.all(np.abs(img.mean(0) - expected) < 4 * stderr + 0.004 * expected), (img.mean(0), expected, stderr)
    bare = float(fresnel_dielectric(np.array(1.0), ETA))
    assert np.max(np.abs(r0 - bare)) > 0.02          # the film's reflection is not the bare one's


def test_white_coated_body_in_a_white_furnace():
    """A lossless body (sigma_a 0) under a coated rough boundary, a sphere in a white sky of
    radiance 1: no pixel's mean exceeds 1 (diffusion on a curved body loses some light, never adds)."""
    m = material("subsurface", sigma_a=(0.0, 0.0, 0.0), sigma_s=(20.0, 20.0, 20.0), roughness=0.1, **SOAP)
    img = renderer.render(_volpath(single_object_scene(m, res=8, fov=10.0)), spp=256, seed=4).reshape(-1, 3)
    se = img.std(0) / np.sqrt(len(img))
    assert np.all(img.mean(0) < 1.0 + 4 * se), (img.mean(0), se)
    assert np.all(img.mean(0) > 0.5)


@pytest.mark.parametrize("params, message", [
    ('"float layer_thickness" [400 25]', 'material "subsurface": layer_thickness describe a stack, which needs "layer_eta"'),
    ('"float layer_eta" [1.68 1.43]', 'material "subsurface": a stack ("layer_eta") needs "layer_thickness"'),
    ('"float layer_eta" [1.68 1.43] "float layer_thickness" [400 25] "float thickness" [300]',
     'thickness belong to one film'),
])
def test_bad_films_are_refused_with_their_line(tmp_path, params, message):
    (tmp_path / "bad.pbrt").write_text(flat_body_scene("subsurface", params))
    with pytest.raises(renderer.errors.SceneError) as e:
        renderer.load_scene(tmp_path / "bad.pbrt")
    assert message in str(e.value) and "bad.pbrt:8" in str(e.value)


def test_uncoated_scenes_compile_no_film():
    """The film's lobes and entry are compiled only into kernels of scenes that have one."""
    from renderer.materials import lobe_features
    assert not lobe_features([material("subsurface", reflectance=(0.5, 0.5, 0.5))])["coated_body"]
    assert lobe_features([material("subsurface", thickness=0.0)])["coated_body"]
