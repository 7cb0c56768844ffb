"""pbrt-v4's ``subsurface`` material: its photon-beam-diffusion table integrates to the effective
albedo, the device's radius sampling has the density the estimator divides by, the reflectance
inversion returns the albedo whose effective albedo is the reflectance, the exit lobe is normalised,
a flat body under a white sky returns what the model promises, and the parameters are refused as
pbrt-v4 refuses them."""
from __future__ import annotations

import numpy as np
import pytest
import warp as wp

import renderer
from renderer.api import init_warp
from renderer.errors import SceneError
from renderer.color import rgb_spectrum
from renderer.materials import beam_diffusion as bd
from bsdf_harness import bsdf_moments
from scenes_py import flat_body_scene
from renderer.materials import material
from renderer.scene.description import MaterialDesc
from renderer.materials.subsurface import exit_normalisation_host
from subsurface_lobes import LOBES
from renderer.materials.tabulated_bssrdf import albedo_from_reflectance, profile, sample_radius

init_warp()
G, ETA = 0.0, 1.33


def test_table_integrates_to_effective_albedo():
    """rho_eff (the spline integral the sampler inverts) equals an independent quadrature of the
    PBD profile on a fine logarithmic radius grid, to the table's interpolation error."""
    t = bd.profile_table(G, ETA)
    for i in (10, 40, 70, 90, 99):
        rho = t.rho[i]
        r = np.concatenate([[0.0], np.geomspace(1e-4, t.radius[-1], 6000)])
        s = bd.single_scattering(rho, 1 - rho, G, ETA, r) + bd.multiple_scattering(rho, 1 - rho, G, ETA, r)
        direct = np.trapezoid(2 * np.pi * r * s, r)
        assert abs(t.rho_eff[i] - direct) < 0.01 * direct + 1e-4, (rho, t.rho_eff[i], direct)
    # more scattering returns more light, and a white body returns about all of it
    assert np.all(np.diff(t.rho_eff) > 0)
    assert 0.95 < t.rho_eff[-1] < 1.05


def test_reflectance_inversion():
    """pbrt-v4's SubsurfaceFromDiffuse: the albedo found for a reflectance has that effective albedo."""
    t = bd.profile_table(G, ETA)
    refl = np.array([0.02, 0.1, 0.3, 0.5, 0.8, 0.95])
    rho = bd.albedo_from_reflectance(t, refl)
    np.testing.assert_allclose(bd.spline_eval(t.rho, t.rho_eff, rho), refl, atol=2e-4)
    assert np.all(np.diff(bd.albedo_from_reflectance(t, np.linspace(0, 1, 101))) > 0)


@wp.kernel
def _profile_kernel(rows: wp.array(dtype=wp.vec4), rho: float, sigma_t: float, r: wp.array(dtype=float),
                    out: wp.array(dtype=wp.vec2)):
    i = wp.tid()
    out[i] = profile(rows, 0, rho, sigma_t, r[i])


@wp.kernel
def _sample_kernel(rows: wp.array(dtype=wp.vec4), rho: float, seed: int, out: wp.array(dtype=float)):
    i = wp.tid()
    rng = wp.rand_init(seed, i)
    out[i] = sample_radius(rows, 0, rho, wp.randf(rng))


@wp.kernel
def _invert_kernel(rows: wp.array(dtype=wp.vec4), refl: wp.array(dtype=float), out: wp.array(dtype=float)):
    i = wp.tid()
    out[i] = albedo_from_reflectance(rows, 0, refl[i])


def _rows() -> wp.array:
    return wp.array(bd.table_rows(G, ETA), dtype=wp.vec4, device="cpu")


@pytest.mark.parametrize("rho", [0.3, 0.8, 0.99])
def test_radius_sampling_density(rho):
    """The device samples radii with the density ``profile`` reports (what the estimator divides by):
    it integrates to 1 over the plane, and a histogram of 200k samples matches it bin by bin."""
    rows = _rows()
    sigma_t = 2.0
    r = np.concatenate([[0.0], np.geomspace(1e-5, 203.0 / sigma_t, 20000)]).astype(np.float32)
    out = wp.zeros(len(r), dtype=wp.vec2, device="cpu")
    wp.launch(_profile_kernel, len(r), inputs=[rows, rho, sigma_t, wp.array(r, dtype=float, device="cpu"), out])
    v = out.numpy()
    ring = 2 * np.pi * r
    assert abs(np.trapezoid(ring * v[:, 1], r) - 1.0) < 5e-3          # a density over the plane
    eff = np.trapezoid(ring * v[:, 0], r)                              # S_r integrates to rho_eff(rho)
    t = bd.profile_table(G, ETA)
    np.testing.assert_allclose(eff, bd.spline_eval(t.rho, t.rho_eff, np.array(rho)), rtol=5e-3)
    n = 200_000
    samples = wp.zeros(n, dtype=float, device="cpu")
    wp.launch(_sample_kernel, n, inputs=[rows, rho, 7, samples])
    x = samples.numpy() / sigma_t
    assert np.all(x >= 0.0)
    edges = np.quantile(x, np.linspace(0, 1, 21))
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (ring[1:] * v[1:, 1] + ring[:-1] * v[:-1, 1]) * np.diff(r))])
    expected = np.diff(np.interp(edges, r, cdf))
    np.testing.assert_allclose(expected, np.full(20, 0.05), atol=4 * np.sqrt(0.05 * 0.95 / n) + 2e-3)


def test_device_inversion_matches_host():
    refl = np.array([0.0, 0.05, 0.4, 0.77, 0.99, 1.0], np.float32)
    out = wp.zeros(len(refl), dtype=float, device="cpu")
    wp.launch(_invert_kernel, len(refl), inputs=[_rows(), wp.array(refl, dtype=float, device="cpu"), out])
    t = bd.profile_table(G, ETA)
    np.testing.assert_allclose(out.numpy(), bd.albedo_from_reflectance(t, refl), atol=1e-5)


def test_exit_lobe_is_normalised():
    """Sw = (1 − F(cos θ)) / (c π) integrates over the hemisphere (times cos) to 1 − 2 FM1 over c:
    1 up to the Fresnel-moment fit's error (c is pbrt-v4's fit of that integral)."""
    mu = np.linspace(0.0, 1.0, 200_001)
    transmitted = 2 * np.trapezoid((1 - bd.fresnel_dielectric(mu, ETA)) * mu, mu)      # ∫(1-F) cos dω / π
    assert abs(transmitted / exit_normalisation_host(ETA) - 1.0) < 2e-3


def test_flat_body_under_white_sky(tmp_path):
    """A smooth flat body seen from above under a white sky of radiance 1: the mirror reflection
    F(0) plus what enters, T = 1 − 2 FM1 of the sky's radiance per unit solid angle and cosine,
    spreads by the profile (its integral: the reflectance, by construction of the inversion) and
    leaves through Sw: L = F(0) + (1 − F(0)) R (1 − 2 FM1) / c. Tests the entry weight, the probe
    density and the exit lobe together."""
    refl = np.array([0.9, 0.5, 0.2])
    body = f'"rgb reflectance" [{refl[0]} {refl[1]} {refl[2]}] "rgb mfp" [0.2 0.1 0.05]'
    (tmp_path / "flat.pbrt").write_text(flat_body_scene("subsurface", body))
    scene = renderer.load_scene(tmp_path / "flat.pbrt")
    img = renderer.render(scene, spp=1024, seed=3).reshape(-1, 3)
    f0 = float(bd.fresnel_dielectric(np.array(1.0), ETA))
    mu = np.linspace(0.0, 1.0, 200_001)
    transmitted = 2 * np.trapezoid((1 - bd.fresnel_dielectric(mu, ETA)) * mu, mu)
    expected = f0 + (1 - f0) * refl * transmitted / exit_normalisation_host(ETA)
    # within the render's noise (pixels are independent); the profile's mass beyond the probe
    # sphere (0.1 %) is lost, as in pbrt-v4
    stderr = img.std(0) / np.sqrt(len(img))
    assert np.all(np.abs(img.mean(0) - expected) < 4 * stderr + 0.003 * expected), (img.mean(0), expected, stderr)
    assert np.all(stderr < 0.02 * expected)


@pytest.mark.parametrize("params, message", [
    ('"string name" "Ketchupp"', 'named medium "Ketchupp" not found'),
    ('"rgb sigma_a" [1 1 1]', '"sigma_a" given without "sigma_s"'),
    ('"rgb mfp" [1 1 1]', 'mfp unused without "reflectance"'),
    ('"string name" "Skin1" "rgb sigma_a" [1 1 1] "rgb sigma_s" [1 1 1]', 'sigma_a, sigma_s unused with "name"'),
    ('"rgb sigma_a" [1 1 1] "rgb sigma_s" [1 1 1] "rgb reflectance" [0.5 0.5 0.5]', 'reflectance unused'),
])
def test_refused_as_pbrt_refuses(tmp_path, params, message):
    (tmp_path / "bad.pbrt").write_text(flat_body_scene("subsurface", params))
    with pytest.raises(SceneError) as e:
        renderer.load_scene(tmp_path / "bad.pbrt")
    assert message in str(e.value) and "bad.pbrt:8" in str(e.value)


def test_named_medium_and_defaults():
    """A name gives pbrt-v4's (sigma_s', sigma_a) in mm^-1 (Jensen et al. 2001's skin 1) and forces
    g = 0 in the table; no coefficients give whole milk's."""
    # material()'s own ``name`` keyword names the material, so the parameter goes in directly
    skin = MaterialDesc("subsurface", {"name": "Skin1", "g": 0.5}, None, "")
    v, _ = renderer.materials.resolve(skin)
    assert v["sigma_s"] == (0.74, 0.88, 1.01) and v["sigma_a"] == (0.032, 0.17, 0.48)
    rows, warning = renderer.materials.subsurface.table_rows(v, None, "rgb3")
    np.testing.assert_array_equal(rows[:bd.N_ROWS], bd.table_rows(0.0, 1.33))
    assert len(rows) == bd.N_ROWS + 2       # and its coefficients' spectra (a coloured medium)
    assert 'non-zero "g" ignored' in warning
    layout = dict((p.name, v) for p, v in renderer.materials.device_layout(material("subsurface"))[0])
    assert layout["sigma_a"] == (0.0011, 0.0024, 0.014) and layout["sigma_s"] == (2.55, 3.21, 3.77)


SPHERE = """LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" 20
Film "rgb" "integer xresolution" [8] "integer yresolution" [8] "string filename" "x.exr"
Sampler "independent" "integer pixelsamples" [64]
Integrator "volpath" "integer maxdepth" [4]
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Material "subsurface" "rgb reflectance" [0.7 0.5 0.3] "rgb mfp" [0.3 0.2 0.1] "float roughness" 0.3
Shape "sphere" "float radius" 0.6
"""


def test_light_sampling_and_bsdf_sampling_agree(tmp_path):
    """A rough subsurface sphere under a white sky rendered with next-event estimation (MIS) and
    with BSDF sampling alone: the same image within noise, so the entry's reflection-only lobe and
    the exit lobe sample the directions their eval_pdf reports."""
    (tmp_path / "sphere.pbrt").write_text(SPHERE)
    scene = renderer.load_scene(tmp_path / "sphere.pbrt")
    a = renderer.render(scene, spp=512, seed=1).reshape(-1, 3)
    b = renderer.render(scene, spp=512, seed=2, nee=False).reshape(-1, 3)
    d = a - b                                   # per pixel: the image cancels, the noise stays
    se = d.std(0) / np.sqrt(len(d))
    assert np.all(np.abs(d.mean(0)) < 4 * se + 2e-3), (a.mean(0), b.mean(0), se)
    assert np.all(se < 0.01 * a.mean(0))


@pytest.mark.parametrize("lobe", ["exit", "surface"])
def test_step_lobes_sample_what_they_evaluate(lobe):
    """The two BSDFs the subsurface step leaves at a vertex, the exit lobe Sw and the boundary's
    reflection alone (rough, 0.3): sample() reports eval_pdf()'s density and value for the direction
    it picks, the density integrates to 1 (the exit lobe) or at most 1, and importance and uniform
    sampling estimate the same albedo. The exit lobe's albedo is eta² (the 1/eta² of the way in
    comes back) times its normalisation."""
    funcs = LOBES[lobe]
    m = bsdf_moments("subsurface", dict(reflectance=(0.5, 0.5, 0.5), roughness=0.3), (0.3, 0.2, 0.9), n=200_000,
                     funcs=funcs)
    assert m["max_inconsistency"] < 2e-3
    tol = 5 * m["albedo_uniform_stderr"] + 1e-3
    assert np.all(np.abs(m["albedo_sampled"] - m["albedo_uniform"]) < tol)
    if lobe == "exit":
        assert abs(m["pdf_integral"] - 1.0) < 0.01
        mu = np.linspace(0.0, 1.0, 200_001)
        transmitted = 2 * np.trapezoid((1 - bd.fresnel_dielectric(mu, ETA)) * mu, mu)
        np.testing.assert_allclose(m["albedo_sampled"], ETA ** 2 * transmitted / exit_normalisation_host(ETA),
                                   rtol=2e-3)
    else:
        assert 0.5 < m["pdf_integral"] <= 1.0 + 0.01
        assert np.all(m["albedo_sampled"] < 0.1)          # the reflection of an index-1.33 boundary


@pytest.mark.parametrize("rgb", [(0.061, 0.97, 1.45), (0.74, 0.88, 1.01), (0.8, 0.6, 0.4), (8.9e-05, 8.4e-05, 0.0)])
def test_upsampled_spectra_have_their_colour(rgb):
    """pbrt-v4's RGBUnboundedSpectrum as fitted here: a spectrum whose colour under D65 (colour-science's
    own integration, not the renderer's tables) is the RGB it came from."""
    import colour
    c, scale, _ = rgb_spectrum.unbounded(rgb)
    lam = np.arange(360.0, 831.0)
    sd = colour.SpectralDistribution(dict(zip(lam, scale * rgb_spectrum.sigmoid(c, lam))))
    shape = colour.SpectralShape(360, 830, 1)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    xyz = colour.sd_to_XYZ(sd, cmfs, d65, method="Integration") / 100.0
    back = colour.XYZ_to_RGB(xyz, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_encoding=False)
    np.testing.assert_allclose(back, rgb, atol=2e-3 * max(rgb))


def test_path_integrator_is_warned(tmp_path):
    """pbrt-v4's "path" integrator ignores BSSRDFs (its subsurface bodies are clear glass); the
    scene renders with subsurface scattering and says so at the Integrator's line."""
    text = flat_body_scene("subsurface", '"rgb reflectance" [0.5 0.5 0.5]', integrator="path")
    (tmp_path / "path.pbrt").write_text(text)
    warnings = renderer.load_scene(tmp_path / "path.pbrt").warnings
    assert any("path.pbrt:5" in w and "ignores" in w and "subsurface" in w for w in warnings), warnings
    (tmp_path / "volpath.pbrt").write_text(flat_body_scene("subsurface", '"rgb reflectance" [0.5 0.5 0.5]'))
    assert not any("ignores" in w for w in renderer.load_scene(tmp_path / "volpath.pbrt").warnings)
