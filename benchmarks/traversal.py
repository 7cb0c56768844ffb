"""Traversal micro-benchmark: Mrays/s of closest-hit and shadow (any-hit) queries through our
4-wide BVH against Warp's ``wp.Mesh``/``wp.Bvh`` queries (what the renderer uses), on the
82k-triangle perf scene and on the beach (about 100k grain instances), one CPU thread per launch.

Rays: camera rays on a pinhole grid; secondary rays from just before each camera hit, uniform over
the hemisphere facing back along the camera ray; shadow rays along those (to the sky, t_max 1e30)
and towards a fixed sun direction. Agreement: the fraction of rays whose hit distances agree
(within 1e-5 relative, or both miss), of those whose (instance, face) also agree, and of shadow
answers that agree.

    python benchmarks/traversal.py [--res 256] [--device cpu] [--repeat 3] [--scenes perf,beach]
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
import warp as wp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".warp-cache"))

from renderer.device.kernel_options import KERNEL_OPTIONS  # noqa: E402
from renderer.device.runtime import init_warp  # noqa: E402
from renderer.geometry.instances import Geometry, build_geometry  # noqa: E402
from renderer.geometry.intersect import intersect, occluded  # noqa: E402
from renderer.geometry.wide_scene import WideBvh, build_wide_bvh  # noqa: E402
from renderer.geometry.wide_traverse import wide_intersect, wide_occluded  # noqa: E402

wp.set_module_options(KERNEL_OPTIONS)


@wp.kernel
def warp_closest(geo: Geometry, o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3), t: wp.array(dtype=float),
                 inst: wp.array(dtype=int), face: wp.array(dtype=int)):
    i = wp.tid()
    h = intersect(geo, o[i], d[i], 1.0e30)
    t[i] = h.t
    inst[i] = h.inst
    face[i] = wp.where(h.inst >= 0, h.face, -1)


@wp.kernel
def wide_closest(geo: Geometry, bvh: WideBvh, o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3),
                 t: wp.array(dtype=float), inst: wp.array(dtype=int), face: wp.array(dtype=int)):
    i = wp.tid()
    h = wide_intersect(bvh, geo.inst_mesh, geo.inst_to_object, o[i], d[i], 1.0e30)
    t[i] = h.t
    inst[i] = h.inst
    face[i] = wp.where(h.inst >= 0, h.face, -1)


@wp.kernel
def warp_shadow(geo: Geometry, o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3), t_max: float,
                out: wp.array(dtype=int)):
    i = wp.tid()
    out[i] = wp.where(occluded(geo, o[i], d[i], t_max), 1, 0)


@wp.kernel
def wide_shadow(geo: Geometry, bvh: WideBvh, o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3), t_max: float,
                out: wp.array(dtype=int)):
    i = wp.tid()
    out[i] = wp.where(wide_occluded(bvh, geo.inst_mesh, geo.inst_to_object, o[i], d[i], t_max), 1, 0)


def perf_scene():
    """The throughput benchmark's sphere and floor, and its camera."""
    from throughput import bench_meshes

    meshes = [(m.vertices, m.faces) for m in bench_meshes()]
    return meshes, np.array([0, 1]), np.stack([np.eye(4)] * 2), (0.0, 1.0, -4.0), (0.0, -0.2, 0.0), 45.0


def beach_scene():
    """The beach's meshes and instances, as the renderer flattens them, and its camera."""
    from renderer.device.scene import flatten_instances
    from renderer.scene import load_description

    desc = load_description(ROOT / "scenes" / "beach.pbrt")
    inst_mesh, _, xf = flatten_instances(desc)
    c2w = np.asarray(desc.camera.camera_to_world, dtype=np.float64)
    eye = c2w[:3, 3]
    return ([(m.positions, m.indices) for m in desc.meshes], inst_mesh, xf, tuple(eye),
            tuple(eye + c2w[:3, 2]), float(desc.camera.fov_deg))


def camera_rays(eye, target, fov_deg: float, res: int) -> tuple[np.ndarray, np.ndarray]:
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    f = target - eye
    f /= np.linalg.norm(f)
    up = np.array([0.0, 1.0, 0.0]) if abs(f[1]) < 0.99 else np.array([1.0, 0.0, 0.0])
    r = np.cross(up, f)
    r /= np.linalg.norm(r)
    u = np.cross(f, r)
    s = np.tan(np.radians(fov_deg) / 2) * (2 * (np.arange(res) + 0.5) / res - 1)
    x, y = np.meshgrid(s, -s)
    d = x.reshape(-1, 1) * r + y.reshape(-1, 1) * u + f
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.broadcast_to(eye, d.shape).copy(), d


def secondary_rays(o, d, t, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    hit = np.isfinite(t) & (t < 1e29)
    p = o[hit] + d[hit] * (t[hit, None] * (1 - 1e-4))
    w = np.random.default_rng(seed).normal(size=p.shape)
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    w = np.where((w * d[hit]).sum(axis=1, keepdims=True) > 0, -w, w)
    return p, w


class Runner:
    def __init__(self, meshes, inst_mesh, xf, device: str, repeat: int):
        self.device, self.repeat = device, repeat
        t0 = time.perf_counter()
        self.geo = build_geometry([(v, f, None, None) for v, f in meshes], inst_mesh,
                                  np.zeros(len(inst_mesh), np.int32), xf, device)
        self.warp_build = time.perf_counter() - t0
        t0 = time.perf_counter()
        self.wide = build_wide_bvh(meshes, inst_mesh, xf, device)
        self.wide_build = time.perf_counter() - t0

    def _time(self, kernel, inputs, n) -> float:
        wp.launch(kernel, dim=n, inputs=inputs, device=self.device)   # load / warm
        # a CPU launch runs on this thread: its CPU time is what the rays cost, whatever else
        # shares the machine (on CUDA, wall time)
        clock = time.thread_time if self.device == "cpu" else time.perf_counter
        best = np.inf
        for _ in range(self.repeat):
            wp.synchronize_device(self.device)
            t0 = clock()
            wp.launch(kernel, dim=n, inputs=inputs, device=self.device)
            wp.synchronize_device(self.device)
            best = min(best, clock() - t0)
        return n / best / 1e6

    def closest(self, o, d):
        n = len(o)
        oa = wp.array(o.astype(np.float32), dtype=wp.vec3, device=self.device)
        da = wp.array(d.astype(np.float32), dtype=wp.vec3, device=self.device)
        outs = []
        rates = []
        for k, extra in ((warp_closest, []), (wide_closest, [self.wide.struct])):
            t = wp.empty(n, dtype=float, device=self.device)
            inst = wp.empty(n, dtype=int, device=self.device)
            face = wp.empty(n, dtype=int, device=self.device)
            rates.append(self._time(k, [self.geo.struct, *extra, oa, da, t, inst, face], n))
            outs.append((t.numpy(), inst.numpy(), face.numpy()))
        (t0, i0, f0), (t1, i1, f1) = outs
        miss0, miss1 = i0 < 0, i1 < 0
        # relative to the ray's coordinate scale: a hit 1 mm from an origin 5 m out carries the
        # float32 error of 5 m, which both intersectors share
        scale = np.maximum(np.abs(t0), np.abs(o).max(axis=1))
        t_ok = (miss0 & miss1) | (~miss0 & ~miss1 & (np.abs(t0 - t1) <= 1e-5 * scale))
        id_ok = t_ok & (i0 == i1) & (f0 == f1)
        return rates, t_ok.mean(), id_ok.mean(), t0

    def shadow(self, o, d, t_max: float):
        n = len(o)
        oa = wp.array(o.astype(np.float32), dtype=wp.vec3, device=self.device)
        da = wp.array(d.astype(np.float32), dtype=wp.vec3, device=self.device)
        outs, rates = [], []
        for k, extra in ((warp_shadow, []), (wide_shadow, [self.wide.struct])):
            out = wp.empty(n, dtype=int, device=self.device)
            rates.append(self._time(k, [self.geo.struct, *extra, oa, da, float(t_max), out], n))
            outs.append(out.numpy())
        return rates, (outs[0] == outs[1]).mean(), outs[0].mean()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scenes", default="perf,beach")
    a = ap.parse_args()
    init_warp()
    print(f"\n{a.res}x{a.res} camera rays and their secondary rays; best of {a.repeat} launches (thread CPU time on the CPU); device {a.device}\n")
    print("| scene | rays | queries | Warp Mrays/s | wide Mrays/s | wide / Warp | t agree | t+inst+face agree |")
    print("|---|---|---:|---:|---:|---:|---:|---:|", flush=True)
    for name in a.scenes.split(","):
        meshes, inst_mesh, xf, eye, target, fov = {"perf": perf_scene, "beach": beach_scene}[name]()
        run = Runner(meshes, inst_mesh, xf, a.device, a.repeat)
        o, d = camera_rays(eye, target, fov, a.res)
        sun = np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])
        rows = []
        (w, v), t_ok, id_ok, t = run.closest(o, d)
        rows.append(("camera", "closest", len(o), w, v, f"{t_ok:.6f}", f"{id_ok:.6f}"))
        so, sd = secondary_rays(o, d, t)
        (w, v), t_ok, id_ok, _ = run.closest(so, sd)
        rows.append(("secondary", "closest", len(so), w, v, f"{t_ok:.6f}", f"{id_ok:.6f}"))
        (w, v), agree, frac = run.shadow(so, sd, 1.0e30)
        rows.append(("secondary", f"shadow ({frac:.0%} blocked)", len(so), w, v, f"{agree:.6f}", ""))
        (w, v), agree, frac = run.shadow(so, np.broadcast_to(sun, so.shape).copy(), 1.0e30)
        rows.append(("to sun", f"shadow ({frac:.0%} blocked)", len(so), w, v, f"{agree:.6f}", ""))
        label = f"{name} ({len(inst_mesh)} inst, build Warp {run.warp_build:.1f} s / wide {run.wide_build:.1f} s)"
        for rays, q, n, w, v, ta, ia in rows:
            print(f"| {label} | {rays} ({n}) | {q} | {w:.3f} | {v:.3f} | {v / w:.2f}x | {ta} | {ia} |", flush=True)


if __name__ == "__main__":
    main()
