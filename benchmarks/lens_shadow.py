"""The sunglasses' shadow in the beach frame, without the sky (issue 33, item 5): the lens shadow's
luminance over the sunlit sand's beside it, against the lens's transmittance along the sun's
direction, and the shadow's colour.

    python benchmarks/lens_shadow.py                       # 540x960 scale, a crop around the shadow
    python benchmarks/lens_shadow.py --res 1080x1920 --spp 64

Sun only: the scene's sky (its ``infinite`` light) is dropped; the camera, exposure and sun are
the frame's. Six renders of a crop around the shadow (after two small full frames that find it),
each through the renderer's API:

- regions, by direct light only (depth 1), where the sand (material AOV) is: in the lens's shadow
  (black with the lenses opaque, lit with the lenses made invisible by the ``interface``
  material: the frame's own shadow is excluded), and sunlit beside it (lit with the lenses
  opaque, within ``--ring`` pixels of the lens's shadow);
- the ratio of mean luminance (linear sRGB Y) in the shadow to the sunlit sand's, by direct light
  (depth 1, what the thin-slab shadow ray computes) and at the scene's depth (the frame, with the
  sand's interreflections in both), with the lenses as the scene has them ("thinslab": shadow rays
  cross them) and opaque to shadow rays ("thinslab" off: every renderer's shadow before, pbrt-v4's,
  Mitsuba 3's, ours; at depth > 1 BSDF sampling still finds the sun's disc through the lens, as
  rare fireflies: the median pixel says what the image shows);
- the expected ratio, computed apart from the renderer's kernels: the lens's T(θ) = T_coat(θ) ·
  tint^(1/cos θ_t) · T_bare(θ) at the sun's incidence on each front vertex of both lenses (the
  coating's T = 1 − R of its stack with the layers' dispersion, in linear sRGB at every nm;
  Fresnel's T for the bare back; the stack scaled by the thickness map at each vertex; no
  interreflection), area-weighted, weighted
  per channel by the sun's colour times the sand's;
- the displayed colour (CIE L*, C*ab, hue; benchmarks/beach_colour.py's conversion) of both regions.

Needs the beach's assets (``assets-gen recipe scenes/beach.pbrt``).
"""
from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np
import trimesh

from beach_colour import displayed_lab
from beach_scene import ASSETS, ROOT, SCENES, sun_direction
from lens_reflection import lens_front, lens_material
from renderer.api import load_scene, open_session, settings_for
from renderer.integrators.aov import render_aovs
from renderer.io.images import write_png
from renderer.materials import material
from renderer.optics.arrays import multilayer_rgb
from renderer.scene.description import SceneDescription

#: linear sRGB luminance weights (Rec. 709)
Y709 = np.array([0.2126, 0.7152, 0.0722])
LENSES = ("lens", "lens-back")


def variant(desc: SceneDescription, lenses: str, res: tuple[int, int], bounds) -> SceneDescription:
    """The frame without its sky, at ``res`` over the pixel ``bounds``, its lenses as the scene has
    them ("through"), opaque to shadow rays ("opaque") or invisible ("removed")."""
    mats = []
    for m in desc.materials:
        if m.name in LENSES and lenses == "opaque":
            m = dataclasses.replace(m, values={**m.values, "thinslab": False})
        elif m.name in LENSES and lenses == "removed":
            m = material("interface", name=m.name)
        mats.append(m)
    film = dataclasses.replace(desc.film, width=res[0], height=res[1], crop_window=None, pixel_bounds=bounds)
    return dataclasses.replace(desc, materials=mats, film=film, lights=[x for x in desc.lights if x.kind != "infinite"])


def rendered(desc: SceneDescription, spp: int, depth: int, aov: bool = False):
    """Linear RGB (and the material AOV's ids) of one render; its seconds."""
    t0 = time.perf_counter()
    session = open_session(desc, settings_for(desc, max_depth=depth))
    session.run(spp)
    img = session.image()
    ids = render_aovs(session.ds, session.settings.seed)["material"][..., 0] if aov else None
    return img, ids, time.perf_counter() - t0


def regions(opaque: np.ndarray, removed: np.ndarray, sand: np.ndarray, ring: int):
    """Masks of the lens's shadow and the sunlit sand beside it, from direct-light renders."""
    from scipy import ndimage

    y_open = removed @ Y709
    level = np.median(y_open[sand & (y_open > 0)])
    y_opaque = opaque @ Y709
    shadow = sand & (y_opaque < 0.02 * level) & (y_open > 0.5 * level)
    shadow = ndimage.binary_erosion(shadow, iterations=1)          # no penumbra, no mixed pixels
    lit = sand & (y_opaque > 0.5 * level)
    beside = lit & ndimage.binary_dilation(shadow, iterations=ring)
    return shadow, beside


def thickness_added(uv: np.ndarray) -> np.ndarray:
    """The lens's thickness map (nm added to the stack) at mesh UVs, bilinear, t flipped as the
    renderer's image textures read it (renderer/textures/evaluate.py)."""
    from scipy import ndimage

    from renderer.io.images import read_exr

    chans, _ = read_exr(ASSETS / "lens_thickness" / "lens_thickness.exr")
    img = np.asarray(next(iter(chans.values())), float)
    h, w = img.shape[:2]
    x, y = uv[:, 0] * w - 0.5, (1.0 - uv[:, 1]) * h - 0.5
    return ndimage.map_coordinates(img.reshape(h, w), [y, x], order=1, mode="nearest")


def expected_transmittance(sun: np.ndarray) -> tuple[np.ndarray, float]:
    """The lenses' RGB T along the sun, area-weighted over both front faces, and the mean angle."""
    lens = lens_material().values
    n_glass = float(np.ravel(lens["eta_inner"])[0])
    tint = np.asarray(lens["tint"], float)
    eta = [1.0, *lens["layer_eta"], n_glass]
    layers = np.asarray(lens["layer_thickness"], float)
    m = np.load(ASSETS / "sunglasses_placement" / "placement.npz")["transform"]
    total, weight, cosines = np.zeros(3), 0.0, []
    for name in ("lens_left", "lens_right"):
        mesh = trimesh.load(ASSETS / "sunglasses" / f"{name}_front.ply", process=False)
        _, n, w = lens_front(mesh, m)
        scale = 1.0 + thickness_added(mesh.visual.uv[mesh.vertex_normals[:, 2] > 0.5]) / layers.sum()
        cos = np.clip(np.abs(n @ sun), 1e-3, 1.0)     # the sun may enter by either face: T is reciprocal
        coat = np.zeros((len(cos), 3))
        bins = np.round(scale, 3)                      # the stack's scale to 0.1 %: one evaluation per value
        for b in np.unique(bins):
            at = bins == b
            coat[at] = 1.0 - multilayer_rgb(cos[at], eta, [0.0] * len(eta), list(layers * b), "reference",
                                            lens.get("layer_cauchyb"))
        sin_t = np.sqrt(1.0 - cos ** 2) / n_glass
        cos_t = np.sqrt(1.0 - sin_t ** 2)
        rs = ((cos - n_glass * cos_t) / (cos + n_glass * cos_t)) ** 2
        rp = ((n_glass * cos - cos_t) / (n_glass * cos + cos_t)) ** 2
        bare = 1.0 - 0.5 * (rs + rp)
        T = coat * tint[None, :] ** (1.0 / cos_t[:, None]) * bare[:, None]
        total += (w[:, None] * T).sum(0)
        weight += w.sum()
        cosines.append((w * cos).sum() / w.sum())
    return total / weight, float(np.degrees(np.arccos(np.mean(cosines))))


def colour_row(name: str, img: np.ndarray, mask: np.ndarray) -> str:
    lab = displayed_lab(img)[mask]
    c = np.hypot(lab[:, 1], lab[:, 2])
    h = np.degrees(np.arctan2(lab[:, 2].mean(), lab[:, 1].mean())) % 360.0
    return f"| {name} | {mask.sum()} | {lab[:, 0].mean():.1f} | {c.mean():.1f} | {h:.0f} |"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", default="540x960", help="the frame's resolution the crop is cut from")
    ap.add_argument("--spp", type=int, default=64, help="samples per pixel of the scene-depth renders")
    ap.add_argument("--ring", type=int, default=6, help="width of the sunlit band beside the shadow, pixels")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "lens_shadow", help="where the crops' PNG goes")
    a = ap.parse_args()
    W, H = (int(x) for x in a.res.split("x"))
    desc = load_scene(SCENES / "beach.pbrt")
    sand_id = [m.name for m in desc.materials].index("sand")
    depth = desc.integrator.max_depth

    # find the shadow in a small full frame, then crop around it at the asked resolution
    lw, lh = W // 4, H // 4
    small = {k: rendered(variant(desc, k, (lw, lh), None), 4, 1, aov=True) for k in ("opaque", "removed")}
    shadow, _ = regions(small["opaque"][0], small["removed"][0], small["opaque"][1] == sand_id, 1)
    ys, xs = np.nonzero(shadow)
    if len(xs) == 0:
        raise SystemExit("no lens shadow found on the sand at the camera's view")
    margin = 6
    bounds = (max(0, int(xs.min() - margin) * 4), min(W, int(xs.max() + 1 + margin) * 4),
              max(0, int(ys.min() - margin) * 4), min(H, int(ys.max() + 1 + margin) * 4))
    print(f"crop x {bounds[0]}..{bounds[1]}, y {bounds[2]}..{bounds[3]} of {W}x{H}")

    direct = {k: rendered(variant(desc, k, (W, H), bounds), 16, 1, aov=(k == "opaque"))
              for k in ("opaque", "removed", "through")}
    sand = direct["opaque"][1] == sand_id
    shadow, beside = regions(direct["opaque"][0], direct["removed"][0], sand, a.ring)
    frame = {k: rendered(variant(desc, k, (W, H), bounds), a.spp, depth) for k in ("through", "opaque", "removed")}
    seconds = sum(r[2] for r in (*direct.values(), *frame.values()))

    sun = sun_direction()
    T, theta = expected_transmittance(sun)
    lights = next(x for x in desc.lights if x.kind == "distant")
    w = np.asarray(lights.values["L"], float) * np.asarray(
        next(m for m in desc.materials if m.name == "sand").values["color"], float)
    expected = float((w * T) @ Y709 / (w @ Y709))
    print(f"lens shadow {shadow.sum()} px, sunlit sand beside it {beside.sum()} px; sun at {theta:.1f} deg "
          f"to the lens fronts' normals (area-weighted); renders {seconds:.0f} s")
    print(f"expected: T along the sun (RGB) {np.round(T, 3)}, luminance ratio on the sand {expected:.3f}")
    print("| render | shadow / sunlit (luminance) | per channel R, G, B | against expected | median pixel ratio |")
    print("|---|---:|---|---:|---:|")
    for name, img in (("direct light, lenses as the scene has them", direct["through"][0]),
                      ("direct light, lenses opaque", direct["opaque"][0]),
                      (f"depth {depth} (the frame), lenses as the scene has them", frame["through"][0]),
                      (f"depth {depth}, lenses opaque", frame["opaque"][0])):
        rgb = img[shadow].mean(0) / img[beside].mean(0)
        ratio = float(img[shadow].mean(0) @ Y709 / (img[beside].mean(0) @ Y709))
        typical = float(np.median(img[shadow] @ Y709) / np.median(img[beside] @ Y709))
        print(f"| {name} | {ratio:.3f} | {', '.join(f'{x:.3f}' for x in rgb)} | {ratio / expected - 1.0:+.1%} "
              f"| {typical:.3f} |")
    through, removed = direct["through"][0], direct["removed"][0]
    lens_T = float(through[shadow].mean(0) @ Y709 / (removed[shadow].mean(0) @ Y709))
    print(f"direct light in the shadow over the same pixels with the lenses removed (the lens's T as rendered): "
          f"luminance {lens_T:.3f} ({lens_T / expected - 1.0:+.1%} against expected), by channel "
          f"{np.round(through[shadow].mean(0) / removed[shadow].mean(0), 3)}")
    scene_T = float(frame["through"][0][shadow].mean(0) @ Y709 / (frame["removed"][0][shadow].mean(0) @ Y709))
    print(f"the same at depth {depth} (the sand's interreflections in both): {scene_T:.3f} "
          f"({scene_T / expected - 1.0:+.1%} against expected)")
    lit = float(removed[shadow].mean(0) @ Y709 / (removed[beside].mean(0) @ Y709))
    print(f"with the lenses removed, the shadow's sand is lit {lit:.3f}x the sunlit sand beside it (its slope and "
          "ripples towards the sun): the shadow / sunlit ratio carries that factor")
    print("\n| region (depth-%d renders, displayed) | pixels | mean L* | mean C*ab | hue of mean a*b* (deg) |" % depth)
    print("|---|---:|---:|---:|---:|")
    print(colour_row("lens shadow, lenses as the scene has them", frame["through"][0], shadow))
    print(colour_row("lens shadow, lenses opaque", frame["opaque"][0], shadow))
    print(colour_row("sunlit sand beside it", frame["through"][0], beside))
    a.out.mkdir(parents=True, exist_ok=True)
    png = a.out / f"lens_shadow_{W}x{H}.png"
    write_png(png, np.concatenate([frame["through"][0], frame["opaque"][0]], 0))
    print(f"wrote {png}: the crop at depth {depth}, lenses as the scene has them above, opaque to shadow rays below")


if __name__ == "__main__":
    main()
