"""Score poses of the beach's conch by how much of its inside (the nacre) the camera sees.

    python benchmarks/conch_pose.py 90,-90,0 140,0,-80 ...     # yaw,tilt_x,tilt_z in degrees

Each pose is placed as the recipe's ``conch-placement`` entry does (``bury``, depth 0.3, on the
beach's sand: build the recipe first). The score is the projected area of the inner surface seen
from the camera, unoccluded by the shell or the sand (sum of area x |cos| / distance², x1000), and
the part of it that the sun also reaches; both by ray casts with Warp. docs/scenes.md quotes it.
"""
from __future__ import annotations

import argparse

import numpy as np
import trimesh
import warp as wp

from beach_scene import ASSETS, blocked, camera_eye, recipe_params, sun_direction
from assets_gen.terrain.placement import PlacementParams, place

CAMERA = camera_eye()
SUN = sun_direction()                                   # towards the sun
POSITION = tuple(recipe_params("conch-placement")["position"])   # (x, z)


def score(yaw: float, tilt: tuple[float, float], sand_near: trimesh.Trimesh) -> tuple[float, float]:
    """(seen, seen and sunlit) projected inner area of the conch buried in this pose."""
    sand = str(ASSETS / "sand" / "sand.ply")
    pose = place(PlacementParams(surface=sand, mesh=str(ASSETS / "conch" / "conch.ply"), mode="bury",
                                 position=POSITION, yaw_deg=yaw, tilt_deg=tilt, depth=0.3))
    m = pose.matrix()
    placed = [trimesh.Trimesh(x.vertices @ m[:3, :3].T + m[:3, 3], x.faces, process=False)
              for x in (trimesh.load(ASSETS / "conch" / name, process=False) for name in ("conch_inner.ply", "conch.ply"))]
    blockers = trimesh.util.concatenate(placed + [sand_near])
    inner = placed[0]
    p, n, area = inner.triangles_center, inner.face_normals, inner.area_faces
    to_cam = CAMERA - p
    dist = np.linalg.norm(to_cam, axis=1)
    to_cam /= dist[:, None]
    cos_cam = (n * to_cam).sum(1)
    side = np.sign(cos_cam)                             # the face's side the camera is on
    o = p + 1e-4 * side[:, None] * n
    seen = (np.abs(cos_cam) > 0.05) & ~blocked(blockers, o, to_cam)
    lit = seen & (side * (n @ SUN) > 0) & ~blocked(blockers, o, np.repeat(SUN[None], len(p), 0))
    weight = area * np.abs(cos_cam) / dist ** 2 * 1e3
    return float(weight[seen].sum()), float(weight[lit].sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("poses", nargs="+", help="yaw,tilt_x,tilt_z in degrees (the recipe's yaw_deg and tilt_deg)")
    args = ap.parse_args()
    wp.config.quiet = True
    sand = trimesh.load(ASSETS / "sand" / "sand.ply", process=False)
    near = np.linalg.norm(sand.triangles_center[:, [0, 2]] - POSITION, axis=1) < 0.25
    sand_near = trimesh.Trimesh(sand.vertices, sand.faces[near], process=False)
    print("| yaw | tilt | seen | seen and sunlit |\n|---:|---|---:|---:|")
    for pose in args.poses:
        yaw, tx, tz = (float(v) for v in pose.split(","))
        seen, lit = score(yaw, (tx, tz), sand_near)
        print(f"| {yaw:g} | [{tx:g}, {tz:g}] | {seen:.3f} | {lit:.3f} |", flush=True)


if __name__ == "__main__":
    main()
