"""``thinfilm``'s tinted clear substrate (``tint``, a sunglass lens): Beer–Lambert in the thin-slab
approximation, tint^(1/(2|cos θ|)) for each direction of a vertex that lies inside. It never adds
energy, is exact at normal incidence (one pass through a parallel slab = tint), stays finite at
grazing angles, and a flat tinted slab renders the closed form of its interreflections."""
from __future__ import annotations

import numpy as np
import pytest

import renderer
from bsdf_harness import bsdf_moments
from renderer.api import init_warp
from renderer.errors import SceneError
from renderer.materials import material
from renderer.scene.description import MeshDesc
from scenes_py import single_object_scene

init_warp()

TINT = (0.8, 0.4, 0.1)
CLEAR = dict(eta_film=1.33, thickness=400.0, eta_inner=1.5, transmission=True)


def bare_fresnel_normal(eta: float) -> float:
    return ((eta - 1) / (eta + 1)) ** 2


@pytest.mark.parametrize("roughness", [0.0, 0.3])
@pytest.mark.parametrize("wo", [(0.3, 0.2, 0.9), (0.9, 0.1, 0.1), (0.4, -0.3, -0.7), (0.95, 0.0, -0.05)],
                         ids=["above", "grazing above", "inside", "grazing inside"])
def test_tint_never_adds_energy(roughness, wo):
    """The same seed draws the same directions (the tint leaves the pdf alone), so every sample
    weight of the tinted lens is at most the clear lens's, channel by channel, and finite."""
    clear = bsdf_moments("thinfilm", CLEAR | dict(roughness=roughness), wo, n=50_000)
    tinted = bsdf_moments("thinfilm", CLEAR | dict(roughness=roughness, tint=TINT), wo, n=50_000)
    assert np.all(np.isfinite(tinted["albedo_sampled"])) and np.all(np.isfinite(tinted["albedo_uniform"]))
    assert np.all(tinted["albedo_sampled"] <= clear["albedo_sampled"] + 1e-7)
    assert np.all(tinted["albedo_sampled"] >= 0.0)
    if wo[2] < 0 or roughness > 0:   # from inside (or through rough facets) some weight is always absorbed
        assert np.all(tinted["albedo_sampled"] < clear["albedo_sampled"])


def test_normal_incidence_is_exact():
    """A 0 nm film at normal incidence: from outside, E[weight] = R + (1 − R) √tint / η² (half
    the pass is charged on the way in); from inside, R·tint + (1 − R) √tint η² (the other half,
    and a whole pass for the internal reflection). In and out of a parallel slab: tint."""
    eta = 1.5
    R = bare_fresnel_normal(eta)
    values = CLEAR | dict(thickness=0.0, tint=TINT)
    t = np.array(TINT)
    above = bsdf_moments("thinfilm", values, (0.0, 0.0, 1.0), n=200_000)
    inside = bsdf_moments("thinfilm", values, (0.0, 0.0, -1.0), n=200_000)
    np.testing.assert_allclose(above["albedo_sampled"], R + (1 - R) * np.sqrt(t) / eta ** 2,
                               atol=5 * above["albedo_sampled_stderr"].max() + 1e-5)
    np.testing.assert_allclose(inside["albedo_sampled"], R * t + (1 - R) * np.sqrt(t) * eta ** 2,
                               atol=5 * inside["albedo_sampled_stderr"].max() + 1e-5)


def test_black_and_clear_channels_at_the_limits():
    """tint 0 absorbs everything that enters, tint 1 is the clear lens exactly, even at grazing
    angles where 1/cos θ is huge (no 0·∞ or 1^∞ NaN)."""
    for wo in [(0.3, 0.2, -0.9), (1.0, 0.0, -1e-7), (0.0, 0.0, -1.0)]:
        clear = bsdf_moments("thinfilm", CLEAR | dict(roughness=0.2), wo, n=20_000)
        m = bsdf_moments("thinfilm", CLEAR | dict(roughness=0.2, tint=(0.0, 1.0, 0.5)), wo, n=20_000)
        assert np.all(np.isfinite(m["albedo_sampled"])) and np.all(np.isfinite(m["albedo_uniform"]))
        assert m["albedo_sampled"][0] == 0.0 and m["albedo_uniform"][0] == 0.0
        assert m["albedo_sampled"][1] == clear["albedo_sampled"][1]


def test_tint_needs_a_clear_substrate():
    with pytest.raises(SceneError, match="transmission"):
        material("thinfilm", tint=0.5)


def slab_mesh(half: float = 1.0, depth: float = 0.05) -> MeshDesc:
    """A flat box |x|, |y| ≤ half, |z| ≤ depth with outward-facing triangles."""
    corners = np.array([[x, y, z] for x in (-half, half) for y in (-half, half) for z in (-depth, depth)], np.float32)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = []
    for a, b, c, d in quads:
        for t in ((a, b, c), (a, c, d)):
            p = corners[list(t)]
            n = np.cross(p[1] - p[0], p[2] - p[0])
            tris.append(t if np.dot(n, p.mean(axis=0)) > 0 else t[::-1])
    return MeshDesc(positions=corners, indices=np.array(tris, np.int32))


def test_flat_tinted_slab_renders_its_closed_form():
    """Seen head-on under a uniform sky of 1, a parallel slab shows everything it reflects and
    transmits: R + (1 − R)² τ / (1 − R τ) with τ = tint per pass (R: the bare face, 0 nm film)."""
    desc = single_object_scene(material("thinfilm", **(CLEAR | dict(thickness=0.0, tint=TINT))), mesh=slab_mesh(),
                               fov=1.0)
    desc.integrator.max_depth = 64
    img = renderer.render(desc, spp=256, thin_film="rgb3", seed=3)
    R = bare_fresnel_normal(1.5)
    tau = np.array(TINT)
    np.testing.assert_allclose(img.mean(axis=(0, 1)), R + (1 - R) ** 2 * tau / (1 - R * tau), atol=5e-3)
