"""The wavefront integrator computes the megakernel's image: same random streams, same float
operations per path, so on the CPU the two images, ray counts and dropped-sample counts are equal
bit for bit, scene by scene. Its small kernels are what a CUDA render launches; the intersection
and shadow kernels fit the GPU budget (128 registers, a 1 KB frame)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from renderer.api import load_scene, open_session, render, settings_for
from renderer.device.scene import upload
from renderer.integrators.kernels import render_kernels, use_wavefront
from renderer.session import RenderStats

ROOT = Path(__file__).resolve().parents[2]
PBRT = ROOT / "tests" / "data" / "pbrt"

#: (scene, sampler or None for the scene's, width, height, spp): together they cover every
#: material family, mixes, alpha cut-outs, dispersion, subsurface scattering, bump maps,
#: environment, distant and area lights, thin slabs, thin films with and without the layered walk
#: in one scene, participating media (a camera inside fog, media behind interfaces and inside
#: glass), and four samplers (checked below).
CASES = [
    (ROOT / "scenes" / "demo.pbrt", None, 32, 18, 2),                 # zsobol; glass, metals, area light
    (ROOT / "scenes" / "demo.pbrt", "independent", 32, 18, 2),
    (PBRT / "dispersion.pbrt", "stratified", 24, 24, 2),
    (PBRT / "material_mix.pbrt", None, 32, 16, 2),
    (PBRT / "shape_alpha.pbrt", None, 32, 16, 2),
    (PBRT / "light_environment.pbrt", None, 24, 24, 2),               # an image environment light
    (ROOT / "scenes" / "sand_patch.pbrt", None, 32, 16, 2),           # disney with subsurface
    (ROOT / "scenes" / "ar_coating.pbrt", None, 32, 18, 2),           # thin film
    (PBRT / "v3_materials_upgraded.pbrt", "halton", 32, 24, 2),       # coatings, a bump map, a mix
    (PBRT / "subsurface_skin.pbrt", None, 24, 24, 2),                 # pbrt-v4's subsurface, spectral body
    (ROOT / "scenes" / "translucent_films.pbrt", None, 24, 14, 2),    # a film on its body: the entry step
    (PBRT / "thin_slab_shadow.pbrt", None, 24, 18, 2),                # shadow rays through a thin lens
    (PBRT / "films_walk.pbrt", None, 32, 18, 2),                      # walking and one-pass films, bump maps
    (PBRT / "bumped_subsurface.pbrt", None, 32, 18, 2),               # bump maps with and without subsurface
    (PBRT / "media_fog.pbrt", "zsobol", 24, 18, 2),                   # the camera in fog, a spot light
    (PBRT / "media_cube.pbrt", None, 36, 16, 2),                      # scattering media behind interfaces
    (PBRT / "media_glass.pbrt", None, 24, 24, 2),                     # an absorbing medium inside glass
]


def _render(case, wavefront: bool, threads: int = 1) -> tuple[np.ndarray, RenderStats]:
    path, sampler, w, h, spp = case
    stats = RenderStats()
    img = render(load_scene(path), spp=spp, width=w, height=h, sampler=sampler, threads=threads, stats=stats,
                 wavefront=wavefront)
    return img, stats


def test_cases_cover_the_features():
    features = [upload(load_scene(c[0]), "cpu", 8, 8).features for c in CASES]
    kinds = {k for f in features for k in f.materials}
    assert {"diffuse", "dielectric", "conductor", "thinfilm", "disney", "coateddiffuse", "subsurface"} <= kinds, kinds
    lights = {k for f in features for k in f.lights}
    assert {"infinite", "distant", "diffuse"} <= lights, lights
    for flag in ("mix", "alpha", "dispersion", "subsurface", "bump", "thin_slabs", "media", "coated_body"):
        assert any(getattr(f, flag) for f in features), flag
    assert any(f.layered and f.unlayered and f.bump for f in features)     # the walk's own kernel
    samplers = {c[1] or load_scene(c[0]).sampler.kind for c in CASES}
    assert {"independent", "stratified", "zsobol", "halton"} <= samplers, samplers


@pytest.mark.parametrize("case", CASES, ids=[f"{c[0].stem}-{c[1] or 'scene'}" for c in CASES])
def test_wavefront_image_equals_megakernel(case):
    mega, ms = _render(case, wavefront=False)
    wave, ws = _render(case, wavefront=True, threads=2)    # two workers: each has its own path buffers
    assert mega.mean() > 0.0
    assert np.array_equal(wave, mega)
    assert ws.rays == ms.rays and ws.bad_samples == ms.bad_samples


def test_resume_across_integrators():
    """A checkpoint of megakernel passes continues under the wavefront into the uninterrupted image."""
    scene = load_scene(CASES[0][0])
    settings = settings_for(scene, width=24, height=12)
    whole = open_session(scene, settings, threads=1, wavefront=False)
    whole.run(4)
    first = open_session(scene, settings, threads=1, wavefront=False)
    first.run(2)
    rest = open_session(scene, settings, threads=1, wavefront=True)
    rest.restore(first.state())
    rest.run(4)
    assert rest.film.spp == 4 and np.array_equal(rest.image(), whole.image())
    assert rest.film.ray_count == whole.film.ray_count


def test_device_default_and_kernels():
    features = upload(load_scene(CASES[0][0]), "cpu", 8, 8).features
    assert use_wavefront("cuda", None) and use_wavefront("cuda:1", None)
    assert not use_wavefront("cpu", None)
    assert use_wavefront("cpu", True) and not use_wavefront("cuda", False)
    names = list(render_kernels(features, False, wavefront=True))
    assert names == ["start", "intersect", "hits", *[f"shade_{k}" for k in features.materials], "shadow",
                     "finish", "film"]
    assert list(render_kernels(features, False, aov=True)) == ["path", "film", "aov"]
    films = upload(load_scene(PBRT / "films_walk.pbrt"), "cpu", 8, 8).features
    assert list(render_kernels(films, False, wavefront=True)) == [
        "start", "intersect", "hits", "bump", "shade_diffuse", "light_thinfilm", "shade_thinfilm",
        "light_thinfilm_walk", "shade_thinfilm_walk", "shadow", "finish", "film"]
    lens = upload(load_scene(PBRT / "thin_slab_shadow.pbrt"), "cpu", 8, 8).features
    assert list(render_kernels(lens, False, wavefront=True))[-4:] == ["shadow", "lenses", "finish", "film"]
    fog = upload(load_scene(PBRT / "media_fog.pbrt"), "cpu", 8, 8).features
    assert list(render_kernels(fog, True, wavefront=True))[:4] == ["start", "intersect", "medium", "hits"]


def test_wavefront_small_kernels_fit_the_gpu_budget():
    """The demo's intersection and shadow kernels compile for sm_90 within 128 registers and a
    1 KB frame (the shading kernels' figures are in docs/gpu.md)."""
    from renderer.device.cuda_compile import TARGET, compile_kernels
    from renderer.integrators.wavefront import intersect_kernel, shadow_kernel

    features = upload(load_scene(CASES[0][0]), "cpu", 8, 8).features
    rows = compile_kernels({"intersect": intersect_kernel(features), "shadow": shadow_kernel(features)}, [90])
    for row in rows:
        assert row.resources.registers <= TARGET.registers, (row.name, row.resources)
        assert row.resources.stack_bytes <= TARGET.stack_bytes, (row.name, row.resources)
