"""A film over the Disney material's subsurface body (renderer.materials.disney_film): a 0 nm film,
or one of the body's own index, is the plain material (per lobe and per image); its lobes sample
what they evaluate; its exit lobe's albedo is the closed form ∫(1 − F_i/2) T_coat/(1 − F) cos/π;
a flat body under a white sky renders R + (T/(1 − F))(0°) k A E_exit; a white body in a white
furnace returns no more than 1; bad films are refused with their line; plain scenes compile none
of it."""
from __future__ import annotations

import numpy as np
import pytest
import warp as wp

import renderer
from bsdf_harness import bsdf_moments
from renderer.api import init_warp
from renderer.materials import disney, disney_film, hooks, lobe_features, material
from renderer.materials.beam_diffusion import fresnel_dielectric
from renderer.materials.bsdf import BSDF, BSDFEval, BSDFSample
from scenes_py import flat_body_scene, single_object_scene
from test_subsurface_film import film_RT

init_warp()
ETA = 1.5                       # Disney's default index: the body's
SOAP = dict(thickness=380.0, eta_film=1.33)
NACRE = dict(layer_eta=[1.68, 1.43], layer_thickness=[400.0, 25.0], repeat=4)
BODY = dict(color=(0.8, 0.5, 0.3), scatterdistance=(0.3, 0.2, 0.1), roughness=0.3)
BALANCE_NODES = 16


def _exit_lobe(module) -> tuple[wp.Function, wp.Function]:
    """A module's Disney (eval_pdf, sample) at a subsurface exit point (flag EXIT)."""

    @wp.func
    def exit_eval(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
        c = b
        c.flags = b.flags | disney.EXIT
        return module.eval_pdf(c, wo, wi)

    @wp.func
    def exit_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
        c = b
        c.flags = b.flags | disney.EXIT
        return module.sample(c, wo, u)

    return exit_eval, exit_sample


#: the exit lobe alone, and the surface lobes of the subsurface material's entry point
LOBES = {"exit": _exit_lobe(disney_film), "surface": (disney_film.eval_pdf, disney_film.sample)}
PLAIN_LOBES = {"exit": _exit_lobe(disney), "surface": (disney.eval_pdf, disney.sample)}


def _mu(n: int = 20000) -> np.ndarray:
    return (np.arange(n) + 0.5) / n


def exit_albedo(film: dict) -> np.ndarray:
    """2∫(1 − (1 − μ)⁵/2) T_coat(μ)/(1 − F(μ)) μ dμ (midpoint rule): the coated exit lobe's albedo."""
    mu = _mu()
    ratio = film_RT(film, mu, ETA)[1] / (1 - fresnel_dielectric(mu, ETA))[:, None]
    return 2 * ((1 - 0.5 * (1 - mu) ** 5)[:, None] * ratio * mu[:, None]).mean(axis=0)


def balance(film: dict, albedo: np.ndarray) -> np.ndarray:
    """k = (1 − a R̄_bare)/(1 − a R̄_coat) with the base colour as the body's effective albedo
    (renderer.materials.film_body.exit_balance, the device's midpoint rule in μ²)."""
    mu = np.sqrt((np.arange(BALANCE_NODES) + 0.5) / BALANCE_NODES)
    t_bare = (1 - fresnel_dielectric(mu, ETA)).mean() / ETA ** 2
    t_coat = film_RT(film, mu, ETA)[1].mean(axis=0) / ETA ** 2
    a = albedo / (t_bare + albedo * (1 - t_bare))
    return (1 - a * (1 - t_bare)) / (1 - a * (1 - t_coat))


@pytest.mark.parametrize("lobe", ["exit", "surface"])
@pytest.mark.parametrize("film", [SOAP, NACRE], ids=["soap", "nacre"])
def test_coated_lobes_sample_what_they_evaluate(lobe, film):
    """sample() reports eval_pdf()'s value and density; importance and uniform sampling agree; the
    exit lobe's albedo is the closed form of the host transfer-matrix film; the surface lobes
    (specular with the film's R, retro-reflection, sheen) stay below 1."""
    m = bsdf_moments("disney", BODY | dict(sheen=0.5) | film, (0.3, 0.2, 0.9), n=200_000, funcs=LOBES[lobe])
    assert m["max_inconsistency"] < 2e-3
    tol = 5 * m["albedo_uniform_stderr"] + 1e-3
    assert np.all(np.abs(m["albedo_sampled"] - m["albedo_uniform"]) < tol), m
    assert abs(m["pdf_integral"] - 1.0) < 0.01
    if lobe == "exit":
        np.testing.assert_allclose(m["albedo_sampled"], exit_albedo(film), rtol=3e-3)
    else:
        assert np.all(m["albedo_sampled"] < 1.0)


PLAIN_EQUIVALENTS = {"0 nm": dict(thickness=0.0, eta_film=1.33), "own index": dict(thickness=380.0, eta_film=ETA)}


@pytest.mark.parametrize("film", list(PLAIN_EQUIVALENTS.values()), ids=list(PLAIN_EQUIVALENTS))
def test_plain_equivalent_films_are_the_plain_material(film):
    """A film 0 nm thick, or of the body's own index (no interface between film and body), changes
    nothing: every lobe to float rounding (1e-5), and a subsurface sphere's image within 1e-4."""
    wo = (0.3, 0.2, 0.9)
    for lobe in LOBES:
        coated = bsdf_moments("disney", BODY | film, wo, n=20_000, funcs=LOBES[lobe])
        plain = bsdf_moments("disney", BODY, wo, n=20_000, funcs=PLAIN_LOBES[lobe])
        for key in ("albedo_uniform", "albedo_sampled", "pdf_integral"):
            np.testing.assert_allclose(coated[key], plain[key], rtol=1e-5, atol=1e-7, err_msg=f"{lobe} {key}")
    images = [renderer.render(single_object_scene(material("disney", **kw), res=8), spp=32, seed=5)
              for kw in (BODY, BODY | film)]
    np.testing.assert_allclose(images[1], images[0], rtol=1e-4, atol=1e-5)


def _film_text(film: dict) -> str:
    if "layer_eta" in film:
        return (f'"float layer_eta" [{" ".join(map(str, film["layer_eta"]))}] "float layer_thickness" '
                f'[{" ".join(map(str, film["layer_thickness"]))}] "integer repeat" [{film["repeat"]}]')
    return f'"float thickness" [{film["thickness"]}] "float eta_film" [{film["eta_film"]}]'


@pytest.mark.parametrize("film", [SOAP, NACRE], ids=["soap", "nacre"])
def test_flat_coated_body_under_white_sky(tmp_path, film):
    """A flat coated Disney body (roughness 0: GGX alpha 1e-3, no retro-reflection) seen from above
    under a white sky (rgb3): the film's reflection R(0°) plus the subsurface route, whose profile
    integrates to the base colour A on a plane: L = R(0°) + (T/(1 − F))(0°) k A E_exit, with
    E_exit the coated exit lobe's albedo and k the exit balance."""
    colour = np.array([0.9, 0.5, 0.2])
    params = (f'"rgb color" [{colour[0]} {colour[1]} {colour[2]}] "float roughness" [0] '
              '"rgb scatterdistance" [0.2 0.1 0.05] ')
    (tmp_path / "flat.pbrt").write_text(flat_body_scene("disney", params + _film_text(film), integrator="path"))
    img = renderer.render(renderer.load_scene(tmp_path / "flat.pbrt"), spp=1024, seed=3,
                          thin_film="rgb3").reshape(-1, 3)
    r0, t0 = (x[0] for x in film_RT(film, np.array([1.0]), ETA))
    bare0 = 1 - float(fresnel_dielectric(np.array(1.0), ETA))
    expected = r0 + t0 / bare0 * balance(film, colour) * colour * exit_albedo(film)
    stderr = img.std(0) / np.sqrt(len(img))
    assert np.all(np.abs(img.mean(0) - expected) < 4 * stderr + 0.004 * expected), (img.mean(0), expected, stderr)
    assert np.max(np.abs(r0 - (1 - bare0))) > 0.02          # the film's reflection is not the bare one's


@pytest.mark.parametrize("film", [SOAP, NACRE], ids=["soap", "nacre"])
def test_white_coated_body_in_a_white_furnace(film):
    """A white subsurface body (A = 1) under a film, a sphere in a white sky of radiance 1: the
    object's mean stays below 1, and the film adds at most 1 % to the plain body's (same seed; the
    plain Disney body itself exceeds 1 where its scatter distance is small against the sphere:
    Burley's lobes are not energy-coupled, test_disney)."""
    means = []
    for kw in ({}, film):
        m = material("disney", color=1.0, scatterdistance=(0.3, 0.3, 0.3), roughness=0.2, **kw)
        desc = single_object_scene(m, res=8, fov=10.0)
        desc.integrator.max_depth = 32
        means.append(renderer.render(desc, spp=512, seed=4).reshape(-1, 3))
    plain, coated = means
    se = (coated - plain).std(0) / np.sqrt(len(coated))
    assert np.all(coated.mean(0) < 1.0), coated.mean(0)
    assert np.all(coated.mean(0) - plain.mean(0) < 0.01 + 4 * se), (coated.mean(0), plain.mean(0), se)
    assert np.all(coated.mean(0) > 0.9)


@pytest.mark.parametrize("params, message", [
    ('"float thickness" [300]', 'coats a subsurface body: it needs a solid'),
    ('"rgb scatterdistance" [0.1 0.1 0.1] "bool thin" true "float thickness" [300]', 'it needs a solid'),
    ('"rgb scatterdistance" [0.1 0.1 0.1] "float thickness" [300] "float flatness" [0.5]',
     'flatness and difftrans (thin sheets) cannot be given with a film'),
    ('"rgb scatterdistance" [0.1 0.1 0.1] "float layer_thickness" [400 25]',
     'material "disney": layer_thickness describe a stack, which needs "layer_eta"'),
    ('"rgb scatterdistance" [0.1 0.1 0.1] "float layer_eta" [1.68 1.43] "float layer_thickness" [400 25] '
     '"float eta_film" [1.4]', 'eta_film belong to one film'),
    ('"rgb scatterdistance" [0.1 0.1 0.1] "float thickness" [-5]', 'thickness'),
])
def test_bad_films_are_refused_with_their_line(tmp_path, params, message):
    (tmp_path / "bad.pbrt").write_text(flat_body_scene("disney", params, integrator="path"))
    with pytest.raises(renderer.errors.SceneError) as e:
        renderer.load_scene(tmp_path / "bad.pbrt")
    assert message in str(e.value) and "bad.pbrt:8" in str(e.value)


def test_plain_disney_compiles_no_film():
    """Disney materials without a film keep the plain functions and their slot layout (the two film
    slots empty, the thin sheets' slots theirs); the film's lobes exist only for a scene with one."""
    plain = lobe_features([material("disney", scatterdistance=(0.1, 0.1, 0.1))])
    assert not plain["coated_disney"]
    assert lobe_features([material("disney", scatterdistance=0.1, thickness=0.0)])["coated_disney"]

    class Features:
        coated_disney = False
    assert hooks(disney, Features()) == (disney.eval_pdf, disney.sample)
    from renderer.materials import device_layout
    layout = device_layout(material("disney", thin=True, flatness=0.3, difftrans=0.7))[0]
    assert [v for _, v in layout[12:]] == [0.3, 0.7, None, None]
