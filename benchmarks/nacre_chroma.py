"""How colourful a nacre stack's reflection is, before any scene: the CIELAB chroma of its
reflectance under D65 (issue 33: why the beach's pearl oyster has 300 nm tablets, and how much
one draw of the thickness disorder decides).

    python benchmarks/nacre_chroma.py                        # tablets 300..500 nm, 5 and 8 periods, 10 draws
    python benchmarks/nacre_chroma.py --tablets 300 400 --periods 5 --angle 35
    python benchmarks/nacre_chroma.py --light 3.91 2.67 1.41   # lit by the beach's sun (lights.pbrt's rgb L)

For each tablet thickness and period count: the stack of scenes/nacre.pbrt (aragonite 1.68 |
organic matrix 1.43, 25 nm, σ 15 % / 30 %) over aragonite, its 1 nm reference reflectance as
linear sRGB (:func:`renderer.optics.arrays.multilayer_rgb`), scaled as the beach's thickness map
scales it (the whole stack by 1 .. 1 + 424 nm / the 5-period 400 nm stack's total, evenly spaced),
then CIELAB (sRGB-encoded, clipped, ``skimage.color.rgb2lab``, D65). Printed per disorder seed:
the chroma C*ab averaged over the map's scales, at the given angle of incidence (default 56°, the
half-angle between the sun and the camera at the oyster). ``--light`` multiplies the reflectance
by a light's linear RGB scaled to luminance 1, as the renderer multiplies a light's RGB by the
film's (a grey reflector of 0.1 under the beach's warm sun has C*ab 17). Still the colour of a
reflectance, not of a pixel: the frame adds the sky, the body under the stack and the exposure.
"""
from __future__ import annotations

import argparse
import sys
import warnings

import numpy as np

warnings.filterwarnings("ignore", message=".*Matplotlib.*")

#: The beach's growth-band map adds up to this many nm to the whole stack (the preview's shell-height).
MAP_MAX_NM = 424.0
ARAGONITE, MATRIX, MATRIX_NM, DISORDER = 1.68, 1.43, 25.0, (0.15, 0.3)


def stack_lab(tablet_nm: float, periods: int, seed: int, scale: float, cos_theta: float,
              light: np.ndarray = np.ones(3)) -> np.ndarray:
    """CIELAB of the stack's reflectance at one thickness scale and angle, under ``light`` (linear RGB)."""
    from skimage.color import rgb2lab

    from renderer.color.rgb import linear_to_srgb, luminance
    from renderer.materials.stack import stack_rows
    from renderer.optics.arrays import multilayer_rgb

    rows = stack_rows({"layer_eta": [ARAGONITE, MATRIX], "layer_thickness": [tablet_nm, MATRIX_NM],
                       "repeat": periods, "layer_disorder": list(DISORDER), "seed": seed}).astype(np.float64)
    eta = [1.0, *rows[:, 0], ARAGONITE]
    rgb = multilayer_rgb(np.array([cos_theta]), eta, np.zeros(len(eta)), rows[:, 3] * scale, mode="reference")[0]
    rgb = rgb * light / float(luminance(light))
    return rgb2lab(np.clip(linear_to_srgb(np.clip(rgb, 0.0, 1.0)), 0.0, 1.0)[None])[0]


def mean_chroma(tablet_nm: float, periods: int, seed: int, angle_deg: float, light: np.ndarray,
                n_scales: int = 7) -> float:
    """C*ab averaged over the thickness map's range of scales."""
    total = 5 * (400.0 + MATRIX_NM)
    scales = np.linspace(1.0, 1.0 + MAP_MAX_NM / total, n_scales)
    cos_t = float(np.cos(np.radians(angle_deg)))
    return float(np.mean([np.hypot(*stack_lab(tablet_nm, periods, seed, s, cos_t, light)[1:]) for s in scales]))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tablets", type=float, nargs="+", default=[300.0, 350.0, 400.0, 500.0])
    ap.add_argument("--periods", type=int, nargs="+", default=[5, 8])
    ap.add_argument("--seeds", type=int, default=10, help="disorder draws: seeds 1..N")
    ap.add_argument("--angle", type=float, default=56.0, help="angle of incidence, degrees")
    ap.add_argument("--light", type=float, nargs=3, default=[1.0, 1.0, 1.0], help="the light's linear RGB (default white)")
    a = ap.parse_args()
    seeds = range(1, a.seeds + 1)
    print(f"C*ab of the reflectance at {a.angle:g} deg under light {a.light}, averaged over the thickness map; "
          f"seeds {seeds.start}..{seeds.stop - 1}")
    print("| tablets (nm) | periods | mean | min | max | " + " | ".join(f"seed {s}" for s in seeds) + " |")
    print("|---:|---:|---:|---:|---:|" + "---:|" * len(seeds))
    for t in a.tablets:
        for p in a.periods:
            c = np.array([mean_chroma(t, p, s, a.angle, np.array(a.light)) for s in seeds])
            print(f"| {t:g} | {p} | {c.mean():.1f} | {c.min():.1f} | {c.max():.1f} | " +
                  " | ".join(f"{x:.1f}" for x in c) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
