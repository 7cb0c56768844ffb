"""Physics of the integrator: furnaces, energy bounds, MIS unbiasedness, determinism, depth of field."""
from __future__ import annotations

import numpy as np
import pytest

import renderer
from renderer.lights import light
from renderer.materials import material
from scenes_py import single_object_scene, sphere_mesh


def object_pixels(img: np.ndarray) -> np.ndarray:
    """The central pixels, all of which see the unit sphere in the default test view."""
    h, w, _ = img.shape
    return img[h // 4: 3 * h // 4, w // 4: 3 * w // 4]


@pytest.mark.parametrize("nee", [True, False])
def test_white_furnace_diffuse(nee):
    """Albedo 1 under a uniform sky of 1 renders 1 everywhere (up to MIS noise with NEE)."""
    mesh = sphere_mesh()
    mesh.normals = None  # flat facets: a convex polyhedron never sees itself, so no path is lost
    desc = single_object_scene(material("diffuse", reflectance=(1.0, 1.0, 1.0)), mesh=mesh)
    img = renderer.render(desc, spp=64, nee=nee)
    assert np.all(np.isfinite(img))
    assert abs(img.mean() - 1.0) < 0.01
    if not nee:
        # without light sampling every path is camera -> sphere -> sky: exactly 1 per sample
        assert np.allclose(img, 1.0, atol=1e-5)


def test_grey_furnace_scales_with_albedo():
    desc = single_object_scene(material("diffuse", reflectance=(0.25, 0.5, 0.75)))
    img = object_pixels(renderer.render(desc, spp=64))
    np.testing.assert_allclose(img.mean(axis=(0, 1)), [0.25, 0.5, 0.75], rtol=0.03)


@pytest.mark.parametrize("roughness", [0.0, 0.02])
def test_dielectric_sphere_conserves_energy(roughness):
    """A glass sphere in a uniform sky neither creates nor loses light: every path escapes to a
    sky of 1 with throughput 1 (radiance scaling by 1/eta^2 in and eta^2 out cancels)."""
    desc = single_object_scene(material("dielectric", eta=1.5, roughness=roughness))
    desc.integrator.max_depth = 64
    img = object_pixels(renderer.render(desc, spp=64))
    assert np.all(np.isfinite(img))
    if roughness == 0:
        np.testing.assert_allclose(img, 1.0, atol=1e-5)
    else:
        # single-scattering GGX has no interreflection between microfacets: it can only lose energy
        assert 0.85 < img.mean() <= 1.0 + 0.01


@pytest.mark.parametrize("roughness", [0.0, 0.05, 0.5, 1.0])
def test_conductor_reflects_at_most_the_sky(roughness):
    """A metal never reflects more than it receives; a perfect (k large) smooth mirror reflects all."""
    desc = single_object_scene(material("conductor", eta=(0.2, 0.9, 1.1), k=(3.9, 2.4, 2.1),
                                                                 roughness=roughness))
    img = object_pixels(renderer.render(desc, spp=64))
    assert np.all(np.isfinite(img))
    assert img.mean(axis=(0, 1)).max() <= 1.0 + 0.02
    assert img.mean() > 0.1


def test_smooth_mirror_reflects_everything():
    desc = single_object_scene(material("conductor", reflectance=(0.9999, 0.9999, 0.9999)))
    img = object_pixels(renderer.render(desc, spp=4))
    np.testing.assert_allclose(img, 1.0, atol=2e-3)


def test_same_seed_same_image_bit_for_bit():
    desc = single_object_scene(material("diffuse", reflectance=(0.5, 0.5, 0.5)))
    desc.lights.append(light("distant", L=2.0, from_=(0.3, 1.0, -0.5), to=(0, 0, 0)))
    a = renderer.render(desc, spp=8, seed=3)
    b = renderer.render(desc, spp=8, seed=3)
    c = renderer.render(desc, spp=8, seed=4)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_passes_are_mergeable_across_thread_counts():
    """Random numbers depend on (seed, sample, pixel) only, not on how rows are split."""
    desc = single_object_scene(material("diffuse", reflectance=(0.5, 0.5, 0.5)))
    a = renderer.render(desc, spp=4, seed=1, threads=1)
    b = renderer.render(desc, spp=4, seed=1, threads=2)
    np.testing.assert_array_equal(a, b)


def test_distant_light_irradiance():
    """A Lambertian plane of albedo rho lit head-on by a distant light of L renders rho L / pi."""
    from scenes_py import look_at
    from renderer.scene.description import MeshDesc

    quad = MeshDesc(positions=np.array([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], np.float32),
                    indices=np.array([[0, 1, 2], [0, 2, 3]], np.int32))
    desc = single_object_scene(material("diffuse", reflectance=(0.5, 0.5, 0.5)), mesh=quad, sky=0.0)
    desc.camera.camera_to_world = look_at((0, 0, -3), (0, 0, 0), (0, 1, 0))
    desc.lights = [light("distant", L=np.pi, from_=(0.0, 0.0, -1.0), to=(0, 0, 0))]
    img = renderer.render(desc, spp=4)
    np.testing.assert_allclose(img, 0.5, rtol=1e-4)
