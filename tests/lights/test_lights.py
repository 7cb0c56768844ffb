"""Environment-map importance sampling: its pdf integrates to 1 over the sphere, samples carry the
pdf and radiance that evaluation gives, and MIS renders match BSDF-only renders."""
from __future__ import annotations

import numpy as np
import pytest
import warp as wp

import renderer
from renderer.api import init_warp
from renderer.io.images import write_exr
from renderer.lights import infinite, kind_id, light
from renderer.lights.sample import light_sampler
from renderer.lights.table import LightTable, Lights
from renderer.sampling.warps import uniform_sphere
from renderer.materials import material
from scenes_py import single_object_scene

init_warp()
_sample_env = light_sampler((infinite,), (kind_id(infinite.NAME),))


@wp.kernel
def _env_check(lights: Lights, seed: int, out: wp.array(dtype=wp.vec4, ndim=2)):
    i = wp.tid()
    rng = wp.rand_init(seed, i)
    d = uniform_sphere(wp.vec2(wp.randf(rng), wp.randf(rng)))
    out[i, 0] = wp.vec4(infinite.pdf(lights, 0, d) * 4.0 * 3.14159265358979, 0.0, 0.0, 0.0)
    s = _sample_env(lights, wp.vec3(0.0), 0.0, wp.vec2(wp.randf(rng), wp.randf(rng)))
    L = infinite.radiance(lights, 0, s.wi)
    out[i, 1] = wp.vec4(s.pdf, infinite.pdf(lights, 0, s.wi), wp.length(L - s.L), 0.0)
    # E[L / pdf] over light samples is the integral of radiance over the sphere
    Ls = wp.vec3(0.0)
    if s.pdf > 0.0:  # as in the integrator: a zero-density sample (a lat-long pole) contributes nothing
        Ls = s.L / s.pdf
    out[i, 2] = wp.vec4(Ls[0], Ls[1], Ls[2], 0.0)
    Lu = infinite.radiance(lights, 0, d) * (4.0 * 3.14159265358979)
    out[i, 3] = wp.vec4(Lu[0], Lu[1], Lu[2], 0.0)


def env_image(w: int, h: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    img = rng.lognormal(0.0, 1.0, size=(h, w, 3)).astype(np.float32)
    img[h // 3, w // 4] = 500.0  # a small bright "sun" pixel
    return img


@pytest.mark.parametrize("shape", [(32, 16), (16, 16)], ids=["latlong", "equal-area"])
def test_env_pdf_and_sampling(tmp_path, shape):
    path = tmp_path / "env.exr"
    write_exr(path, env_image(*shape))
    rot = np.array([[1, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1]], dtype=np.float64)
    table = LightTable()
    table.add(kind_id(infinite.NAME), infinite.ROW, infinite.entry(light("infinite", rot, filename=path), None))
    L, keep = table.upload("cpu")
    n = 400_000
    out = wp.zeros((n, 4), dtype=wp.vec4, device="cpu")
    wp.launch(_env_check, dim=n, inputs=[L, 7, out], device="cpu")
    o = out.numpy()
    assert abs(o[:, 0, 0].mean() - 1.0) < 0.02                      # ∫ pdf dω = 1
    np.testing.assert_allclose(o[:, 1, 0], o[:, 1, 1], rtol=1e-3)    # sample pdf == pdf()
    assert o[:, 1, 2].max() < 1e-3                                    # sample radiance == eval
    # importance and uniform sampling estimate the same ∫ L dω
    np.testing.assert_allclose(o[:, 2, :3].mean(axis=0), o[:, 3, :3].mean(axis=0), rtol=0.05)


@pytest.mark.parametrize("shape", [(32, 16), (16, 16)], ids=["latlong", "equal-area"])
def test_mis_render_matches_bsdf_sampling(tmp_path, shape):
    """Light sampling with MIS is unbiased: it converges to what pure BSDF sampling gives."""
    path = tmp_path / "env.exr"
    img = env_image(*shape, seed=2)
    img[img > 100] = 20.0  # keep BSDF-only variance testable at low spp
    write_exr(path, img)
    desc = single_object_scene(material("diffuse", reflectance=(0.7, 0.7, 0.7)))
    desc.lights[0] = light("infinite", filename=path)
    a = renderer.render(desc, spp=256, nee=True)
    b = renderer.render(desc, spp=256, nee=False)
    assert np.all(np.isfinite(a)) and np.all(np.isfinite(b))
    np.testing.assert_allclose(a.mean(axis=(0, 1)), b.mean(axis=(0, 1)), rtol=0.03)
