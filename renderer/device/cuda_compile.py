"""Compiling a render's CUDA kernels ahead of time, on a machine with or without a GPU.

Warp ships NVRTC, so a cubin for any architecture it supports can be built here and written into
Warp's kernel cache (``$WARP_CACHE_PATH``) under the very name a render on such a GPU looks up:
the module's content hash, and ``.smXX.cubin`` (renderer kernels always load cubins, see
:func:`renderer.device.runtime.init_warp`, so what runs is what was compiled and measured). Users
compile on a login node and render on GPU nodes, or warm a cluster's shared cache. Each cubin is
then read for its resources (:mod:`renderer.device.cubin`)."""
from __future__ import annotations

import os
import re
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from renderer.device.cubin import KernelResources, read_resources
from renderer.errors import RenderError

#: The architecture compiled for when none is named and no GPU is present: sm_90 (H100/H200).
DEFAULT_ARCH = 90


@dataclass(frozen=True)
class Budget:
    """Per-thread resources a render kernel may use on sm_90."""

    registers: int
    stack_bytes: int


#: The design's budget (DESIGN.md, "GPU budget"): 128 registers (16 resident warps per SM) and a
#: 1 KB local frame, spills included.
TARGET = Budget(registers=128, stack_bytes=1024)
#: What CI holds the representative scene's megakernel to today (tests/device; its wavefront
#: kernels, what a CUDA render launches, are held to TARGET): the figures measured when it was set,
#: so a change that needs more stack or breaks CUDA compilation fails. The megakernel's registers
#: are at the hardware's 255 (docs/gpu.md). The frame was
#: 1,136 B; the multiscatter lobes (846abb8) made it 1,392 B, compiled into every dielectric and
#: conductor kernel even where no material turns them on. Kernels now compile only the lobes the
#: scene's materials reach (Features.multiscatter, .layered, .smooth): 1,104 B (860 KB of code),
#: and the budget holds that with 48 B to spare.
BUDGET = Budget(registers=255, stack_bytes=1152)


def every_feature():
    """The feature set of a scene that uses every material, light family and kernel option at once
    (cut-outs, mixes, bump maps, subsurface, dispersion, media): the kernels the budget must hold
    whatever a scene combines."""
    from renderer import lights, materials
    from renderer.device.scene import Features

    kinds = tuple(lights.REGISTRY)
    return Features(materials=tuple(sorted(materials.REGISTRY)), bump=True, lights=kinds,
                    escaping=tuple(k for k in kinds if hasattr(lights.REGISTRY[k], "escaped")), nee=True,
                    subsurface=True, alpha=True, mix=True, dispersion=True, media=True)


#: Seconds between "still compiling" lines: a GPU user must never wait in silence.
HEARTBEAT_SECONDS = 15.0


@dataclass(frozen=True)
class CompiledKernel:
    """One render kernel compiled for one architecture."""

    name: str                        # "path", "film", "aov"
    arch: int
    seconds: float                   # NVRTC's wall time (0 when the cache already held it)
    cached: bool
    cubin: Path
    resources: KernelResources


def parse_archs(text: str | None) -> list[int]:
    """``"sm_75,sm_86,90"`` → [75, 86, 90]; None → the local GPU's architecture, else sm_90.
    Architectures NVRTC cannot target are refused, naming the ones it can."""
    import warp as wp

    from renderer.device.runtime import init_warp

    init_warp()
    if text is None:
        return [wp.get_device("cuda").arch] if wp.is_cuda_available() else [DEFAULT_ARCH]
    supported = sorted(wp._src.context.runtime.nvrtc_supported_archs)
    archs = []
    for item in text.split(","):
        digits = item.strip().lower().removeprefix("sm_").removeprefix("sm")
        if not digits.isdigit() or int(digits) not in supported:
            raise RenderError(f"--arch: {item.strip()!r} is not an architecture this Warp's NVRTC compiles for "
                              f"(supported: {', '.join(f'sm_{a}' for a in supported)})")
        archs.append(int(digits))
    return list(dict.fromkeys(archs))


def cubin_path(module, arch: int) -> Path:
    """Where Warp's runtime looks for ``module``'s cubin on a GPU of ``arch`` (CUDA launches use
    256-thread blocks, whose module variant this is)."""
    import warp as wp

    ident = module.get_module_identifier(block_dim=256)
    return Path(wp.config.kernel_cache_dir) / ident / f"{ident}.sm{arch}.cubin"


def compile_kernels(kernels: dict[str, object], archs: list[int],
                    say: Callable[[str], None] = lambda _m: None, workers: int | None = None) -> list[CompiledKernel]:
    """Compile each kernel for each architecture into the kernel cache (skipping what it holds)
    and read back its resources, in the order given. ``workers`` modules compile at once (default:
    one per CPU): Warp generates each module's source under its codegen lock, then NVRTC runs
    outside the GIL, so the wall time nears the longest kernel's rather than the sum; the cubins
    are the same bytes as a serial build's. The shading kernels and the megakernel, the long
    compiles, start first. ``say`` gets a line before each compile and every
    :data:`HEARTBEAT_SECONDS` while NVRTC runs."""
    from renderer.device.runtime import init_warp

    init_warp()
    jobs = [(arch, name, kernel) for arch in archs for name, kernel in kernels.items()]
    order = sorted(range(len(jobs)), key=lambda j: not _long(jobs[j][1]))
    with ThreadPoolExecutor(max_workers=max(1, workers or os.cpu_count() or 1)) as pool:
        futures = {j: pool.submit(_compile_one, *jobs[j], say) for j in order}
        return [futures[j].result() for j in range(len(jobs))]


def compile_scene(scene, settings, device: str, arch: str | None, wavefront: bool | None, aov: bool,
                  say: Callable[[str], None] = lambda _m: None) -> str:
    """``render --compile-only``: every kernel a render of ``scene`` with ``settings`` on ``device``
    launches (the wavefront's or, with ``wavefront`` False, the megakernel; the AOV kernel with
    ``aov``), compiled for the architectures ``arch`` names (:func:`parse_archs`) into the kernel
    cache; returns their :func:`table`."""
    from renderer.device.scene import upload
    from renderer.integrators.kernels import render_kernels, use_wavefront

    if not device.startswith("cuda"):
        raise RenderError("--compile-only compiles CUDA kernels: add --device cuda")
    archs = parse_archs(arch)
    # the kernels depend on the scene's features only, which an upload to the CPU determines
    ds = upload(scene, "cpu", settings.width, settings.height, nee=settings.nee, thin_film=settings.thin_film)
    kernels = render_kernels(ds.features, settings.sampler.name == "independent", aov,
                             use_wavefront(device, wavefront))
    t0 = time.perf_counter()
    rows = compile_kernels(kernels, archs, say)
    if any(not r.cached for r in rows):
        say(f"compile: {len(rows)} kernels in {time.perf_counter() - t0:.0f} s wall")
    return table(rows)


def _long(name: str) -> bool:
    """The kernels whose compile takes minutes: a material's shading or light sample (wavefront) or the whole path."""
    return name.startswith(("shade_", "light_")) or name == "path"


def _compile_one(arch: int, name: str, kernel, say: Callable[[str], None]) -> CompiledKernel:
    import warp as wp

    module = kernel.module
    target = cubin_path(module, arch)
    cached = target.is_file()
    say(f"compile: {name} kernel for sm_{arch}" + (" (in the cache)" if cached else " ..."))
    t0 = time.perf_counter()
    with _heartbeat(say, f"compile: {name} kernel for sm_{arch}", t0):
        wp.compile_aot_module(module, arch=arch, use_ptx=False)
    seconds = 0.0 if cached else time.perf_counter() - t0
    if not target.is_file():
        raise RenderError(f"NVRTC wrote no cubin at {target}")
    return CompiledKernel(name, arch, seconds, cached, target, _entry(read_resources(target), kernel.key))


def _entry(found: list[KernelResources], key: str) -> KernelResources:
    """The forward entry point of the kernel ``key`` among a cubin's (Warp names it after the key
    with every non-word character made ``_``, then a hash)."""
    prefix = re.sub(r"\W", "_", key) + "_"
    for r in found:
        if r.name.startswith(prefix) and r.name.endswith("_cuda_kernel_forward"):
            return r
    raise RenderError(f"the cubin has no entry point for kernel {key} (found: {', '.join(r.name for r in found)})")


class _heartbeat:
    """A daemon thread that reports progress while a blocking native compile runs."""

    def __init__(self, say: Callable[[str], None], what: str, t0: float):
        self.say, self.what, self.t0 = say, what, t0
        self.done = threading.Event()

    def __enter__(self) -> "_heartbeat":
        def beat() -> None:
            while not self.done.wait(HEARTBEAT_SECONDS):
                self.say(f"{self.what}: still compiling ({time.perf_counter() - self.t0:.0f} s)")

        threading.Thread(target=beat, daemon=True).start()
        return self

    def __exit__(self, *exc) -> None:
        self.done.set()


def table(rows: list[CompiledKernel]) -> str:
    """The per-kernel table ``--compile-only`` prints (a Markdown table, pasteable into docs)."""
    head = ("| kernel | arch | registers | stack frame B | LDL / STL | shared B | params B | code KB | compile s |\n"
            "|---|---|---:|---:|---:|---:|---:|---:|---:|")
    lines = [head]
    for r in rows:
        q = r.resources
        spills = "n/a" if q.local_loads < 0 else f"{q.local_loads} / {q.local_stores}"
        secs = "cached" if r.cached else f"{r.seconds:.1f}"
        lines.append(f"| {r.name} | sm_{r.arch} | {q.registers} | {q.stack_bytes} | {spills} | {q.shared_bytes} | "
                     f"{q.param_bytes} | {q.code_bytes / 1024:.0f} | {secs} |")
    return "\n".join(lines)
