"""CUDA without a GPU: render kernels compile for sm_90 through Warp's NVRTC, land in the kernel
cache under the name a GPU render looks up, and stay within the GPU budget
(:data:`renderer.device.cuda_compile.BUDGET`) that docs/gpu.md explains."""
from __future__ import annotations

from pathlib import Path
from types import MethodType, SimpleNamespace

import pytest
import warp as wp

from renderer.cli import main
from renderer.device.cubin import read_resources, tool
from renderer.device.cuda_compile import BUDGET, TARGET, compile_kernels, cubin_path, every_feature, parse_archs
from renderer.device.runtime import init_warp

ROOT = Path(__file__).resolve().parents[2]
#: The scene whose kernels CI compiles: glass, metals, an area light, a soft sun, depth of field.
REPRESENTATIVE = ROOT / "scenes" / "demo.pbrt"


def gpu_like(arch: int, driver: tuple[int, int]) -> SimpleNamespace:
    """A stand-in CUDA device whose format, architecture and suffix come from Warp's own Device
    methods, so the name below is the one ``Module.load`` computes on such a GPU."""
    from warp._src.context import Device, runtime

    dev = SimpleNamespace(is_cpu=False, is_cuda=True, arch=arch, alias="cuda:0", is_cubin_supported=True,
                          runtime=SimpleNamespace(driver_version=driver, toolkit_version=runtime.toolkit_version))
    for name in ("get_cuda_output_format", "get_cuda_compile_arch", "_get_cuda_arch_suffix"):
        setattr(dev, name, MethodType(getattr(Device, name), dev))
    return dev


def test_cubin_is_what_a_gpu_render_loads():
    """A driver newer than the toolkit would make Warp choose PTX for sm_75; the renderer's Warp
    loads cubins for the exact architecture, and finds the one compiled here without compiling."""
    from renderer.device.film import accumulate

    init_warp()
    assert wp.config.cuda_output == "cubin"
    module = accumulate.module
    [row] = compile_kernels({"film": accumulate}, [90])
    gpu = gpu_like(90, driver=(99, 0))
    assert gpu.get_cuda_output_format() == "cubin" and gpu.get_cuda_compile_arch() == 90
    ident = module.get_module_identifier(block_dim=256)
    looked_up = Path(wp.config.kernel_cache_dir) / ident / module._get_compile_output_name(gpu, block_dim=256)
    assert looked_up == row.cubin == cubin_path(module, 90) and looked_up.is_file()
    module.get_module_hash(256)
    # Module.load's own step: False means "cached, nothing compiled"
    assert module._compile(gpu, str(looked_up.parent), looked_up.name, 90, options=module.resolved_options[256]) is False


def test_cubin_resources_are_read():
    from renderer.device.film import accumulate

    [row] = compile_kernels({"film": accumulate}, [90])
    [entry] = [r for r in read_resources(row.cubin) if r.name.startswith("accumulate_")]
    assert 0 < entry.registers <= 255 and entry.code_bytes > 1000 and entry.param_bytes > 0
    assert entry.stack_bytes == 0       # a few integer operations need no local memory
    if tool("nvdisasm"):
        assert entry.local_loads == 0 and entry.local_stores == 0


def test_parallel_compile_writes_the_serial_cubins(tmp_path, monkeypatch):
    """Kernels compiled side by side (one thread each) are byte for byte the cubins a serial build
    writes, under the same names: Warp's code generation is locked, and NVRTC's output depends on
    the source alone."""
    from renderer.api import load_scene
    from renderer.device.film import accumulate
    from renderer.device.scene import upload
    from renderer.integrators.wavefront import intersect_kernel, shadow_kernel

    features = upload(load_scene(REPRESENTATIVE), "cpu", 8, 8).features
    kernels = {"film": accumulate, "intersect": intersect_kernel(features), "shadow": shadow_kernel(features)}
    built = {}
    for workers in (1, 3):
        monkeypatch.setattr(wp.config, "kernel_cache_dir", str(tmp_path / f"workers{workers}"))
        rows = compile_kernels(kernels, [90], workers=workers)
        assert [r.name for r in rows] == list(kernels) and not any(r.cached for r in rows)
        built[workers] = {r.cubin.relative_to(tmp_path / f"workers{workers}"): r.cubin.read_bytes() for r in rows}
    assert built[1] == built[3]


@pytest.mark.parametrize("text,why", [("sm_12", "not an architecture"), ("gpu", "not an architecture")])
def test_bad_arch_refused(text, why, capsys):
    assert main([str(REPRESENTATIVE), "--device", "cuda", "--compile-only", "--arch", text]) == 2
    assert why in capsys.readouterr().err


def test_compile_only_needs_cuda(capsys):
    assert main([str(REPRESENTATIVE), "--compile-only"]) == 2
    assert "--device cuda" in capsys.readouterr().err


def test_archs_parse():
    assert parse_archs("sm_75, 86,sm_90,sm_90") == [75, 86, 90]


def _compiled(capsys, *flags: str, scene: Path = REPRESENTATIVE) -> dict[str, tuple[int, int]]:
    """Registers and frame bytes per kernel of ``scene`` (the demo), from ``--compile-only``'s table (sm_90)."""
    assert main([str(scene), "--device", "cuda", "--compile-only", "--arch", "sm_90", "--quiet",
                 *flags]) == 0
    rows = [line.split("|")[1:-1] for line in capsys.readouterr().out.splitlines()[2:]]
    return {r[0].strip(): (int(r[2]), int(r[3])) for r in rows}


def test_representative_scene_compiles_within_budget(capsys):
    """The demo's megakernel (``--no-wavefront``: what scenes with media launch on CUDA) and the
    film's accumulation compile for sm_90 and fit the budget."""
    figures = _compiled(capsys, "--no-wavefront")
    assert set(figures) == {"path", "film"}
    for name, (registers, stack) in figures.items():
        assert registers <= BUDGET.registers, (name, registers)
        assert stack <= BUDGET.stack_bytes, (name, stack)


def test_representative_scene_wavefront_fits_the_target(capsys):
    """What a CUDA render of the demo launches with ``--denoise``, the wavefront's kernels (its shading
    kernels under the register cap), the film's accumulation and the AOV pass in steps (as one kernel
    213 registers), fits the design's budget: 128 registers and a frame within 1 KB per kernel."""
    figures = _compiled(capsys, "--denoise")
    assert set(figures) == {"start", "intersect", "hits", "shade_conductor", "shade_dielectric", "shade_diffuse",
                            "shadow", "finish", "film", "aov_hits", "aov_conductor", "aov_dielectric", "aov_diffuse",
                            "aov_guides"}
    for name, (registers, stack) in figures.items():
        assert registers <= TARGET.registers, (name, registers)
        assert stack <= TARGET.stack_bytes, (name, stack)


def test_bump_and_lens_steps_fit_the_target():
    """A bump map's texture program runs in the wavefront's bump step, which fits the design's budget
    under the register cap, and a scene with thin lenses traces their faces in the lens step, so its
    shadow kernel stays the plain any-hit query's size (with the faces' walk inside it the beach's
    was 215 registers and a 912 B frame: docs/gpu.md, "The bump step, the lens step and the walk's
    own kernel"). The lens step fits too, with the coating's optics inlined into it (out of line, the
    beach's frame was 1,200 B: docs/gpu.md, "The lens step and the thin film's coating")."""
    from renderer.api import load_scene
    from renderer.device.scene import upload
    from renderer.integrators.wavefront import bump_kernel, lens_kernel, shadow_kernel

    data = ROOT / "tests" / "data" / "pbrt"
    bumped = upload(load_scene(data / "films_walk.pbrt"), "cpu", 8, 8).features
    lenses = upload(load_scene(data / "thin_slab_shadow.pbrt"), "cpu", 8, 8).features
    assert bumped.bump and lenses.thin_slabs
    kernels = {"bump": bump_kernel(bumped), "shadow": shadow_kernel(lenses), "lenses": lens_kernel(lenses)}
    for row in compile_kernels(kernels, [90]):
        assert row.resources.registers <= TARGET.registers, (row.name, row.resources)
        assert row.resources.stack_bytes <= TARGET.stack_bytes, (row.name, row.resources)


def test_subsurface_probe_step_holds_the_bvh_traversal():
    """Subsurface scattering's probe rays run in the wavefront's probe step, so the shading kernel of
    a scene with subsurface scattering holds no BVH traversal (the BVH's stacks are the probe
    kernel's 34,816 B of shared memory per block) and its frame is smaller (sand_patch's
    `shade_disney` was 1,728 B with the probe inside: docs/gpu.md, "The subsurface probe step")."""
    from renderer.api import load_scene
    from renderer.device.scene import upload
    from renderer.integrators.shader_queues import shaders
    from renderer.integrators.wavefront import probe_kernel, shade_kernel

    features = upload(load_scene(ROOT / "scenes" / "sand_patch.pbrt"), "cpu", 8, 8).features
    assert features.subsurface
    shader = next(sh for sh in shaders(features) if sh.kind == "disney")
    probe, shade = compile_kernels({"probe_disney": probe_kernel(features, False, shader),
                                    "shade_disney": shade_kernel(features, False, shader)}, [90])
    assert shade.resources.shared_bytes < probe.resources.shared_bytes, (shade.resources, probe.resources)
    assert shade.resources.stack_bytes < 1728, shade.resources


def test_tabulated_subsurface_probe_fits_the_target():
    """pbrt-v4's subsurface material's probe step (its tabulated profile, the spline inversion that
    samples the radius and the spectral body, beside the BVH's probe loop) fits the design's budget
    under the register cap: 2,256 B of frame in disney_film and translucent_films before the BSDF's
    slots, the body's channels and the table's rows were read at constant indices, 1,088 B while a
    film's entry (the coating's out-of-line optics at six sites) was computed in it, not in a step
    of its own before it (docs/gpu.md, "The tabulated subsurface probe"). Compiled from the smallest
    scene with a film on the body, both steps, and from the smallest without one."""
    from renderer.api import load_scene
    from renderer.device.scene import upload
    from renderer.integrators.shader_queues import shaders
    from renderer.integrators.wavefront import entry_kernel, probe_kernel

    coated = upload(load_scene(ROOT / "scenes" / "translucent_films.pbrt"), "cpu", 8, 8).features
    bare = upload(load_scene(ROOT / "tests" / "data" / "pbrt" / "subsurface_skin.pbrt"), "cpu", 8, 8).features
    assert coated.coated_body and not bare.coated_body
    shader, bare_shader = (next(sh for sh in shaders(f) if sh.kind == "subsurface") for f in (coated, bare))
    for row in compile_kernels({"entry_subsurface": entry_kernel(coated, True, shader),
                                "probe_subsurface": probe_kernel(coated, True, shader),
                                "probe_subsurface_bare": probe_kernel(bare, True, bare_shader)}, [90]):
        assert row.resources.registers <= TARGET.registers, row.resources
        assert row.resources.stack_bytes <= TARGET.stack_bytes, row.resources


def test_media_steps_fit_the_target():
    """A scene with participating media renders with the wavefront on CUDA: its medium step (delta
    tracking, the light sample and phase sampling at a scattering) and its shadow kernel (ratio
    tracking across interfaces) fit the design's budget under the register cap (the megakernel they
    replace on CUDA: 255 registers, docs/gpu.md "Media")."""
    from renderer.api import load_scene
    from renderer.device.scene import upload
    from renderer.integrators.wavefront import medium_kernel, shadow_kernel

    media = upload(load_scene(ROOT / "tests" / "data" / "pbrt" / "media_cube.pbrt"), "cpu", 8, 8).features
    assert media.media
    for row in compile_kernels({"medium": medium_kernel(media), "shadow": shadow_kernel(media)}, [90]):
        assert row.resources.registers <= TARGET.registers, (row.name, row.resources)
        assert row.resources.stack_bytes <= TARGET.stack_bytes, (row.name, row.resources)


def test_every_feature_medium_and_aov_first_hit_fit_the_target():
    """With every feature at once (``every_feature``: every light kind, cut-outs,
    mixes, bump maps, media), the medium step and the AOV pass's first hit and bump step fit the
    design's budget. The medium step was 1,088 B of frame: tracking read its colour channel and its
    majorant grid's axis at run time (vectors kept in the frame) and the cut-outs' query inlined its
    traversal twice; the first hit was 1,472 B: two traversals per query, and three texture programs
    (cut-outs, mixes, bump maps) until bump maps went to ``aov_bump`` (docs/gpu.md, "The media step
    and the AOVs' first hit with every feature"). Only these three kernels compile (about a minute)."""
    from renderer.integrators.aov_steps import aov_bump_kernel, aov_hits_kernel
    from renderer.integrators.wavefront import medium_kernel

    every = every_feature()
    kernels = {"medium": medium_kernel(every), "aov_hits": aov_hits_kernel(every), "aov_bump": aov_bump_kernel(every)}
    for row in compile_kernels(kernels, [90]):
        assert row.resources.registers <= TARGET.registers, (row.name, row.resources)
        assert row.resources.stack_bytes <= TARGET.stack_bytes, (row.name, row.resources)


@pytest.mark.parametrize("scene", ["films_walk.pbrt", "coatedconductor.pbrt"])
def test_split_shading_scenes_fit_the_target(capsys, scene):
    """What a CUDA render with ``--denoise`` launches for the materials the wavefront shades in two
    kernels (``light_<kind>`` and ``shade_<kind>``): thin films with and without the layered walk,
    bump maps, and the walk between a rough coat and a rough conductor, each kernel within the
    design's budget (one kernel each, before the split and the shared part's local arrays went:
    up to 3,264 B of frame; docs/gpu.md, "The light sample and the BSDF sample apart")."""
    figures = _compiled(capsys, "--denoise", scene=ROOT / "tests" / "data" / "pbrt" / scene)
    assert any(name.startswith("light_") for name in figures), figures
    for name, (registers, stack) in figures.items():
        assert registers <= TARGET.registers, (name, registers)
        assert stack <= TARGET.stack_bytes, (name, stack)


def test_rough_multiscattering_films_fit_the_target():
    """The thin-film kernels of a scene with rough films that count multiple scattering (nacre's;
    films_walk's rough film does not): the compensation lobe of a clear rough film (compiled in
    wherever a rough film may multiscatter) reads the coating at 22 node cosines, and its 72 node
    values crossed the coating's calls at the sampled facet and at wi (``shade_thinfilm`` 1,032 B,
    ``light_thinfilm`` 960 B before those calls were ordered around the nodes: docs/gpu.md, "The
    thin film's nodes")."""
    from renderer.api import load_scene, settings_for
    from renderer.device.scene import upload
    from renderer.integrators.kernels import render_kernels

    desc = load_scene(ROOT / "scenes" / "nacre.pbrt")
    settings = settings_for(desc)
    features = upload(desc, "cpu", 8, 8, thin_film=settings.thin_film).features
    assert features.multiscatter and "thinfilm" not in features.smooth
    kernels = {name: k for name, k in render_kernels(features, settings.sampler.name == "independent", aov=True,
                                                     wavefront=True).items() if "thinfilm" in name}
    assert set(kernels) == {"light_thinfilm", "shade_thinfilm", "aov_thinfilm"}, set(kernels)
    for row in compile_kernels(kernels, [90]):
        assert row.resources.registers <= TARGET.registers, (row.name, row.resources)
        assert row.resources.stack_bytes <= TARGET.stack_bytes, (row.name, row.resources)


def test_every_feature_thin_film_bsdf_halves_fit_the_target():
    """With every feature at once, the thin film's light and BSDF halves fit the design's budget. The
    BSDF half (``shade_thinfilm``) was 1,072 B of frame: the compensation lobe of a clear rough film
    kept the coating at its nodes from both sides (72 values) across the optics' calls that produce
    them; one side at a time, the other taken again where wi is on it, it is 1,008 B (docs/gpu.md,
    "The thin film's nodes"). Only these two kernels compile (about two minutes)."""
    from renderer.integrators.kernels import render_kernels

    every = every_feature()
    kernels = {name: k for name, k in render_kernels(every, False, wavefront=True).items()
               if name in ("light_thinfilm", "shade_thinfilm")}
    assert len(kernels) == 2, set(kernels)
    for row in compile_kernels(kernels, [90]):
        assert row.resources.registers <= TARGET.registers, (row.name, row.resources)
        assert row.resources.stack_bytes <= TARGET.stack_bytes, (row.name, row.resources)


def test_gpu_check_refuses_without_a_gpu():
    import subprocess
    import sys

    if wp.is_cuda_available():
        pytest.skip("this machine has a GPU: make gpu-check runs for real")
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "gpu_check.py"), "--out", "/nonexistent/x"],
                          capture_output=True, text=True)
    assert done.returncode == 2 and "no CUDA GPU" in done.stderr
    assert not Path("/nonexistent/x").exists()


def test_gpu_check_pipeline_on_the_cpu(tmp_path):
    """The scene comparison of make gpu-check, run CPU against CPU: the same seed on the same
    device is the same image, so the ratio is 0 and the verdict holds."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "gpu_check.py"), "--device", "cpu",
                           "--out", str(tmp_path), "--scenes", str(ROOT / "scenes" / "ar_coating.pbrt"),
                           "--skip", "compile", "tests", "mitsuba", "beach", "--spp", "2", "--width", "16"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    report = (tmp_path / "report.md").read_text()
    assert "| ar_coating.pbrt |" in report and "| 0.00 | same within noise |" in report
