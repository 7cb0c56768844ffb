"""Throughput benchmark: an 82k-triangle diffuse sphere on a floor under a uniform sky,
256x256, depth 8. Prints samples/s and rays/s for this renderer (diffuse-only kernel and a kernel
compiled with every material) and, when ``mitsuba`` is installed, for Mitsuba 3 on the same scene.
Also per CPU second of the process (all threads: both renderers use every core), the number to
compare on a machine that other jobs share. Our kernels use the default sampler (zsobol).

    python benchmarks/throughput.py [--spp 64] [--device cpu] [--res 256]
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
os.environ.setdefault("WARP_CACHE_PATH", str(Path(__file__).resolve().parents[1] / ".warp-cache"))

from scenes_py import look_at  # noqa: E402

from renderer.lights import light  # noqa: E402
from renderer.materials import material  # noqa: E402
from renderer.scene.description import (CameraDesc, FilmDesc, InstanceSetDesc,  # noqa: E402
                                        MeshDesc, SamplerDesc, SceneDescription, ShapeDesc)

DEPTH = 8


def bench_meshes() -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    sphere = trimesh.creation.icosphere(subdivisions=6, radius=1.0)        # 81,920 triangles
    floor = trimesh.Trimesh(vertices=[[-10, -1, -10], [10, -1, -10], [10, -1, 10], [-10, -1, 10]],
                            faces=[[0, 2, 1], [0, 3, 2]])
    return sphere, floor


def our_scene(res: int, all_materials: bool) -> SceneDescription:
    """The benchmark scene; with ``all_materials`` two tiny spheres hidden under the floor carry a
    dielectric and a conductor, so the kernel contains every material but renders the same image."""
    sphere, floor = bench_meshes()
    desc = SceneDescription(camera=CameraDesc(camera_to_world=look_at((0, 1, -4), (0, -0.2, 0), (0, 1, 0)), fov_deg=45),
                            film=FilmDesc(width=res, height=res), sampler=SamplerDesc(spp=16, seed=0))
    desc.integrator.max_depth = DEPTH
    meshes = [sphere, floor]
    desc.materials.append(material("diffuse", reflectance=(0.7, 0.7, 0.7)))
    if all_materials:
        meshes += [trimesh.creation.icosphere(1, radius=0.01)] * 2
        desc.materials += [material("dielectric", eta=1.5),
                           material("conductor", roughness=0.2)]
    for i, m in enumerate(meshes):
        desc.meshes.append(MeshDesc(positions=m.vertices.astype(np.float32), indices=m.faces.astype(np.int32)))
        desc.shapes.append(ShapeDesc(mesh=i, material=max(0, i - 1) if i >= 2 else 0))
        xf = np.eye(4)
        xf[:3, 3] = (0, -5, i) if i >= 2 else 0
        desc.instance_sets.append(InstanceSetDesc(shapes=[i], transforms=xf[None]))
    desc.lights.append(light("infinite"))
    return desc


def run_ours(res: int, spp: int, device: str, all_materials: bool) -> dict:
    import renderer.api as api

    api.init_warp()
    desc = our_scene(res, all_materials)
    first = api.RenderStats()
    api.render(desc, spp=1, device=device, stats=first)  # compile (or load from cache) the kernel
    session = api.open_session(desc, api.settings_for(desc), device=device)
    c0 = time.process_time()           # the passes only, as stats.seconds and Mitsuba's mi.render
    stats = session.run(spp)
    cpu = time.process_time() - c0
    kind = "diffuse+dielectric+conductor" if all_materials else "diffuse-only"
    return {"name": f"ours ({kind} kernel, {device})", "seconds": stats.seconds, "cpu_seconds": cpu,
            "samples_per_s": stats.samples_per_second, "rays_per_s": stats.rays_per_second,
            "load_s": first.compile_seconds}


def run_mitsuba(res: int, spp: int, variants: list[str]) -> list[dict]:
    # Debian's default libLLVM 14/15 crashes Dr.Jit's LLVM backend; libllvm19 works
    llvm19 = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
    if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(llvm19):
        os.environ["DRJIT_LIBLLVM_PATH"] = llvm19
    try:
        import mitsuba as mi
    except ImportError:
        print("mitsuba not installed: skipping the side-by-side (pip install mitsuba)")
        return []
    sphere, floor = bench_meshes()
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        sphere.export(f"{tmp}/sphere.ply")
        floor.export(f"{tmp}/floor.ply")
        for variant in variants:
            try:
                mi.set_variant(variant)
            except Exception as e:  # LLVM missing: see README for libllvm19
                print(f"mitsuba {variant} unavailable: {e}")
                continue
            bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7, 0.7, 0.7]}}
            scene = mi.load_dict({
                "type": "scene",
                "integrator": {"type": "path", "max_depth": DEPTH + 1},  # Mitsuba counts the camera segment
                "sensor": {"type": "perspective", "fov": 45, "fov_axis": "smaller",
                           "to_world": mi.ScalarTransform4f().look_at(origin=[0, 1, -4], target=[0, -0.2, 0], up=[0, 1, 0]),
                           "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
                           "sampler": {"type": "independent", "sample_count": spp}},
                "sphere": {"type": "ply", "filename": f"{tmp}/sphere.ply", "bsdf": bsdf},
                "floor": {"type": "ply", "filename": f"{tmp}/floor.ply", "bsdf": bsdf},
                "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1, 1, 1]}},
            })
            mi.render(scene, spp=1)  # warm-up / JIT
            t0, c0 = time.perf_counter(), time.process_time()
            img = mi.render(scene, spp=spp)
            np.asarray(img)
            dt, cpu = time.perf_counter() - t0, time.process_time() - c0
            out.append({"name": f"mitsuba {variant}", "seconds": dt, "cpu_seconds": cpu,
                        "samples_per_s": res * res * spp / dt,
                        "rays_per_s": float("nan"), "load_s": float("nan")})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--mitsuba-variants", default="llvm_ad_rgb,scalar_rgb",
                    help="comma-separated Mitsuba variants to time beside ours (make gpu-check: cuda_ad_rgb,llvm_ad_rgb)")
    a = ap.parse_args()
    print(f"\n{a.res}x{a.res}, {a.spp} spp, depth {DEPTH}, 82k-triangle sphere + floor, uniform sky\n")
    print("| renderer | seconds | M samples/s | M rays/s | CPU s (all threads) | M samples / CPU s | "
          "first kernel load s (cold = compile) | vs ours diffuse-only (CPU) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|", flush=True)
    base = None
    runs = [lambda: [run_ours(a.res, a.spp, a.device, False)], lambda: [run_ours(a.res, a.spp, a.device, True)],
            lambda: run_mitsuba(a.res, a.spp, a.mitsuba_variants.split(","))]
    for run in runs:
        for r in run():
            per_cpu = a.res * a.res * a.spp / r["cpu_seconds"]
            base = base or per_cpu
            print(f"| {r['name']} | {r['seconds']:.2f} | {r['samples_per_s'] / 1e6:.3f} | {r['rays_per_s'] / 1e6:.3f} | "
                  f"{r['cpu_seconds']:.2f} | {per_cpu / 1e6:.3f} | {r['load_s']:.2f} | {per_cpu / base:.2f}x |", flush=True)


if __name__ == "__main__":
    main()
