"""A film over a translucent body: the ``subsurface`` material with a film on its boundary (a
diffusion BSSRDF, renderer.materials.film_body) against the exact volumetric reference, a closed
``thinfilm`` with ``transmission`` (same film, same eta) around a homogeneous medium of the same
sigma_a, sigma_s and g under volpath. The same comparison without the film (``dielectric`` around
the medium against the bare ``subsurface``) separates the diffusion approximation's own error
from what coupling the film adds.

``--model disney``: the diffusion body is the ``disney`` material with the film over its subsurface
body (renderer.materials.disney_film) instead: colour = the medium's effective albedo (pbrt-v4's
table at sigma_s / sigma_t, this eta), scatterdistance = 1 / sigma_t, eta the same, roughness
0.2^(1/4) (Disney's alpha = roughness², the others' alpha = sqrt(0.2)); ``--volume-from`` takes the
reference's means from an earlier results file of the same resolution, spp and seed.

Shapes: a sphere and a slab (a box 6 x 6 x 1 seen from above), under a uniform sky and under a
soft sun (a distant light of 5° angular radius at 45° elevation). Boundaries are rough
(roughness 0.2, no multiple-scattering compensation on either side), so the sun reaches the
medium through the boundary's glossy transmission. Metrics on the pixels the object covers
entirely (found by the renderer itself: a black object before a white sky renders 0 there): the mean per channel and
its relative difference, the CIELAB hue of the means and their ΔE00 (sky-lit: the sky's white is 1).

    WARP_CACHE_PATH=.warp-cache .venv/bin/python benchmarks/film_body.py [--res 48] [--spp 256] [--out docs/images]
"""
from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

#: A skin-like body in scene units (Jensen et al. 2001's skin 1 x 10 per unit: mfp 0.07–0.13 on a sphere of radius 1).
SIGMA_A = (0.32, 1.7, 4.8)
SIGMA_S = (7.4, 8.8, 10.1)
ETA = 1.33
FILM = '"float thickness" [350] "float eta_film" [1.6]'
ROUGH = '"float roughness" [0.2]'
SPHERE_CAM = 'LookAt 0 0 -5  0 0 0  0 1 0\nCamera "perspective" "float fov" [26]'
SLAB_CAM = 'LookAt 0 6 0  0 0 0  0 0 1\nCamera "perspective" "float fov" [30]'
SPHERE = 'Shape "sphere" "float radius" [1]'
SLAB = ('Shape "trianglemesh" "point3 P" [-3 -0.5 -3  3 -0.5 -3  3 -0.5 3  -3 -0.5 3  -3 0.5 -3  3 0.5 -3  3 0.5 3  -3 0.5 3] '
        '"integer indices" [0 1 2 0 2 3  4 6 5 4 7 6  0 4 5 0 5 1  1 5 6 1 6 2  2 6 7 2 7 3  3 7 4 3 4 0]')
SKY = 'LightSource "infinite" "rgb L" [1 1 1]'
SUN = 'LightSource "distant" "point3 from" [1 1.4142 -1] "point3 to" [0 0 0] "rgb L" [3 3 3] "float angularradius" [5]'


def disney_body(color: list[float] | None = None) -> str:
    """The ``disney`` parameters of the same body: its effective albedo (or ``color``) and mean free path."""
    from renderer.materials.beam_diffusion import profile_table
    st = np.add(SIGMA_A, SIGMA_S)
    table = profile_table(0.0, ETA)
    albedo = np.interp(np.divide(SIGMA_S, st), table.rho, table.rho_eff) if color is None else np.asarray(color)
    return (f'"rgb color" [{" ".join(f"{x:.4f}" for x in albedo)}] "rgb scatterdistance" '
            f'[{" ".join(f"{x:.5f}" for x in 1.0 / st)}] "float eta" [{ETA}] "float roughness" [{0.2 ** 0.25:.4f}]')


def scene_text(shape: str, light: str, body: str, film: bool, res: int, depth: int,
               color: list[float] | None = None) -> str:
    """``body``: "diffusion" (the subsurface material), "disney" (its subsurface body) or "volume" (a
    closed boundary around a medium)."""
    cam = SPHERE_CAM if shape == "sphere" else SLAB_CAM
    geometry = SPHERE if shape == "sphere" else SLAB
    head = (f'{cam}\nFilm "rgb" "integer xresolution" [{res}] "integer yresolution" [{res}] "string filename" "x.exr"\n'
            f'Sampler "independent"\nIntegrator "volpath" "integer maxdepth" [{depth}]\nWorldBegin\n'
            f'{SKY if light == "sky" else SUN}\n')
    coeffs = f'"rgb sigma_a" [{" ".join(map(str, SIGMA_A))}] "rgb sigma_s" [{" ".join(map(str, SIGMA_S))}]'
    if body == "disney":
        return head + f'Material "disney" {disney_body(color)} {FILM if film else ""}\n{geometry}\n'
    if body == "diffusion":
        return head + (f'Material "subsurface" {coeffs} "float eta" [{ETA}] {ROUGH} {FILM if film else ""}\n'
                       f'{geometry}\n')
    boundary = (f'Material "thinfilm" "bool transmission" true "float eta_inner" [{ETA}] {FILM} {ROUGH} '
                f'"bool multiscatter" false' if film else f'Material "dielectric" "float eta" [{ETA}] {ROUGH}')
    return head + (f'MakeNamedMedium "body" "string type" "homogeneous" {coeffs} "float g" [0]\n'
                   f'AttributeBegin\nMediumInterface "body" ""\n{boundary}\n{geometry}\nAttributeEnd\n')


def mask(shape: str, res: int) -> np.ndarray:
    """Pixels the object covers entirely: a black diffuse object before a white sky, one bounce, 64 spp."""
    import renderer
    cam = SPHERE_CAM if shape == "sphere" else SLAB_CAM
    text = (f'{cam}\nFilm "rgb" "integer xresolution" [{res}] "integer yresolution" [{res}] "string filename" "x.exr"\n'
            f'Sampler "independent"\nIntegrator "volpath" '
            f'"integer maxdepth" [1]\nWorldBegin\n{SKY}\nMaterial "diffuse" "rgb reflectance" [0 0 0]\n'
            f'{SPHERE if shape == "sphere" else SLAB}\n')
    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "m.pbrt").write_text(text)
        img = renderer.render(renderer.load_scene(Path(d) / "m.pbrt"), spp=64, seed=1)
    return img.max(axis=-1) == 0.0


def render(text: str, spp: int, seed: int) -> tuple[np.ndarray, float]:
    import renderer
    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "s.pbrt").write_text(text)
        t0 = time.perf_counter()
        img = renderer.render(renderer.load_scene(Path(d) / "s.pbrt"), spp=spp, seed=seed)
        return img, time.perf_counter() - t0


def lab(rgb: np.ndarray) -> np.ndarray:
    import colour
    xyz = colour.RGB_to_XYZ(np.maximum(rgb, 0.0), colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=False)
    return colour.XYZ_to_Lab(xyz)


def compare(diffusion: np.ndarray, volume: np.ndarray, m: np.ndarray, scale: float) -> dict:
    """Means over the mask, their relative difference per channel, hues and ΔE00 (colours over ``scale``)."""
    return compare_means(diffusion[m].mean(0), volume[m].mean(0), volume[m].std(0) / np.sqrt(m.sum()), scale)


def compare_means(a: np.ndarray, b: np.ndarray, se, scale: float) -> dict:
    """The comparison of the diffusion model's means ``a`` with the reference's ``b`` (standard error ``se``)."""
    import colour
    se = np.asarray(se)
    la, lb = lab(a / scale), lab(b / scale)
    hue = lambda l: float(np.degrees(np.arctan2(l[2], l[1])) % 360)
    return {"diffusion": a.round(4).tolist(), "volume": b.round(4).tolist(), "volume_se": se.round(4).tolist(),
            "rel_diff": ((a - b) / b).round(4).tolist(), "hue_diffusion": round(hue(la), 1),
            "hue_volume": round(hue(lb), 1), "dE00": round(float(colour.delta_E(la, lb, method="CIE 2000")), 2)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", type=int, default=48)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--depth", type=int, default=256, help="path depth (the medium's scattering events count)")
    ap.add_argument("--out", type=Path, default=None, help="folder for the PNG strips and results.json")
    ap.add_argument("--only", default="", help="e.g. sphere/sky: one configuration")
    ap.add_argument("--table", type=Path, default=None, help="print the tables of a results.json and stop")
    ap.add_argument("--model", choices=("subsurface", "disney"), default="subsurface", help="the diffusion model")
    ap.add_argument("--volume-from", type=Path, default=None, help="the reference's means from this results.json")
    ap.add_argument("--disney-color", type=float, nargs=3, default=None, help="the disney body's colour (default: "
                    "the medium's effective albedo)")
    ap.add_argument("--suffix", default="", help="added to the output files' names")
    args = ap.parse_args()
    if args.table:
        print(tables(json.loads(args.table.read_text())))
        return
    from renderer.io.images import write_png
    results = {}
    for shape in ("sphere", "slab"):
        m = mask(shape, args.res)
        for light in ("sky", "sun"):
            if args.only and args.only != f"{shape}/{light}":
                continue
            strip = []
            for film in (False, True):
                imgs = {}
                key = f"{shape}/{light}/{'film' if film else 'bare'}"
                model = "diffusion" if args.model == "subsurface" else "disney"
                for body in (model, "volume") if args.volume_from is None else (model,):
                    imgs[body], secs = render(scene_text(shape, light, body, film, args.res, args.depth,
                                                         args.disney_color), args.spp, seed=7)
                    print(f"{key}/{body}: {secs:.1f} s", flush=True)
                scale = 1.0 if light == "sky" else 3.0
                if args.volume_from is None:
                    results[key] = compare(imgs[model], imgs["volume"], m, scale)
                    strip += [imgs["volume"], imgs[model]]
                else:
                    ref = json.loads(args.volume_from.read_text())[key]
                    results[key] = compare_means(imgs[model][m].mean(0), np.array(ref["volume"]), ref["volume_se"],
                                                 scale)
                    strip += [imgs[model]]
                print(key, json.dumps(results[key]), flush=True)
            if args.out:
                args.out.mkdir(parents=True, exist_ok=True)
                prefix = "film_body" if args.model == "subsurface" else f"film_body_{args.model}{args.suffix}"
                write_png(args.out / f"{prefix}_{shape}_{light}.png", np.concatenate(strip, axis=1))
    if args.out:
        model = "" if args.model == "subsurface" else f"_{args.model}"
        (args.out / f"film_body{model}{args.suffix}_results.json").write_text(json.dumps(results, indent=1))
    print(tables(results))


def tables(results: dict) -> str:
    """The comparison (diffusion against volume, per configuration) and the film's own effect: its
    image over the bare one's, per channel, in each model, and the quotient of the two (1: the
    diffusion model changes the colour exactly as the volumetric reference does)."""
    out = ["| configuration | volume (R, G, B) | diffusion − volume, relative | hue volume / diffusion | ΔE00 |",
           "|---|---|---|---|---|"]
    for key, r in results.items():
        rel = ", ".join(f"{100 * x:+.1f} %" for x in r["rel_diff"])
        out.append(f"| {key} | {', '.join(f'{x:.3f}' for x in r['volume'])} | {rel} | {r['hue_volume']}° / "
                   f"{r['hue_diffusion']}° | {r['dE00']} |")
    out += ["", "| shape / light | film / bare, volume | film / bare, diffusion | coupling error (quotient − 1) |",
            "|---|---|---|---|"]
    for key in results:
        if key.endswith("/film") and key[:-4] + "bare" in results:
            film, bare = results[key], results[key[:-4] + "bare"]
            vol = np.array(film["volume"]) / np.array(bare["volume"])
            dif = np.array(film["diffusion"]) / np.array(bare["diffusion"])
            out.append(f"| {key[:-5]} | {', '.join(f'{x:.3f}' for x in vol)} | {', '.join(f'{x:.3f}' for x in dif)} | "
                       f"{', '.join(f'{100 * x:+.1f} %' for x in dif / vol - 1)} |")
    return "\n".join(out)

if __name__ == "__main__":
    main()
