"""What one material costs a CUDA kernel: micro-kernels that load a BSDF at a surface point and
call the material dispatch once (``eval_pdf`` or ``sample``), built from the same
``shading_functions(features)`` the path kernel uses, compiled for sm_90 without a GPU, with
``--compile-only``'s columns (registers, frame, LDL/STL, code, NVRTC seconds).

    python benchmarks/material_kernels.py thinfilm --hooks eval sample [--rough] [--multiscatter] [--layered]

Without flags the materials are smooth, single scattering and without the layered walk (the
features of ``scenes/ar_coating.pbrt``); ``--rough --multiscatter --layered`` compiles every lobe.

A path kernel holds much else besides (the BVH query, lights, the sampler); a micro-kernel shows
what a change to one material does, in a minute of NVRTC instead of ten. (No ``from __future__
import annotations``: the kernel's annotations name types imported inside a function, which Warp
could not resolve from strings.)"""
import argparse
import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]


def micro_kernel(features, hook: str):
    """A kernel that loads material 0 at a surface point made from the thread id and calls the
    dispatch's ``hook`` ("eval" or "sample") once, writing what it returns."""
    import warp as wp

    from renderer.color.rgb_weights import RgbWeightTable
    from renderer.device.kernel_options import KERNEL_OPTIONS
    from renderer.geometry.intersect import Surface
    from renderer.integrators.shading import load_bsdf, shading_functions
    from renderer.materials import Materials
    from renderer.textures import Textures

    shading = shading_functions(features)
    call = shading.eval_pdf if hook == "eval" else shading.sample
    is_eval = hook == "eval"

    @wp.kernel(module="unique", module_options=KERNEL_OPTIONS)
    def one_bsdf(mat: Materials, tex: Textures, spectral: RgbWeightTable, spectral_n: int,
                 out: wp.array(dtype=wp.vec4)):
        tid = wp.tid()
        x = float(tid) * 0.001
        s = Surface()
        s.p = wp.vec3(x, 0.5 * x, 1.0)
        s.ng = wp.vec3(0.0, 0.0, 1.0)
        s.ns = s.ng
        s.uv = wp.vec2(x, 1.0 - x)
        s.dpdu = wp.vec3(1.0, 0.0, 0.0)
        s.dpdv = wp.vec3(0.0, 1.0, 0.0)
        b = load_bsdf(mat, tex, spectral, spectral_n, 0, s)
        b.wavelength_u = x
        wo = wp.normalize(wp.vec3(x, 0.3, 1.0))
        if wp.static(is_eval):
            ev = call(b, wo, wp.normalize(wp.vec3(-x, 0.2, 0.9)))
            out[tid] = wp.vec4(ev.f[0], ev.f[1], ev.f[2], ev.pdf)
        else:
            bs = call(b, wo, wp.vec3(x, 0.5, 0.25))
            out[tid] = wp.vec4(bs.weight[0], bs.wi[1], bs.wi[2], bs.pdf)

    return one_bsdf


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("materials", nargs="+", help="material types the dispatch switches over")
    ap.add_argument("--hooks", nargs="+", default=["eval", "sample"], choices=["eval", "sample"])
    ap.add_argument("--multiscatter", action="store_true", help="compile the energy-compensation lobes")
    ap.add_argument("--layered", action="store_true", help="compile thinfilm's layered walk")
    ap.add_argument("--rough", action="store_true", help="compile the rough (GGX) lobes")
    ap.add_argument("--arch", default="sm_90")
    ap.add_argument("--cache", type=Path, help="kernel cache (default: a new, empty one, so seconds are NVRTC's)")
    a = ap.parse_args()
    os.environ["WARP_CACHE_PATH"] = str(a.cache or tempfile.mkdtemp(prefix="material_kernels_"))
    from renderer.device.cuda_compile import compile_kernels, parse_archs, table
    from renderer.device.scene import Features

    kinds = tuple(sorted(a.materials))
    features = Features(materials=kinds, bump=False, lights=(), escaping=(), multiscatter=a.multiscatter,
                        layered=a.layered, smooth=() if a.rough else kinds)
    print(f"features: {features}", file=sys.stderr, flush=True)
    kernels = {f"{'+'.join(a.materials)} {h}": micro_kernel(features, h) for h in a.hooks}
    rows = compile_kernels(kernels, parse_archs(a.arch), lambda m: print(m, file=sys.stderr, flush=True))
    print(table(rows))


if __name__ == "__main__":
    main()
