"""Make the small images the light reference scenes read (light_*.pbrt): a goniometric diagram
(square, equal-area, RGB whose mean is what pbrt-v4 uses), a projector slide (3:2, RGB, an
asymmetric pattern so a flip or a wrong field of view shows) and an environment map (square,
equal-area; an 8-bit PNG, because pbrt-v4's ``illuminance`` weights an EXR's channels in the
file's B, G, R order: docs/pbrt-v4.md). Deterministic; run once, the images are committed.

    python tests/data/pbrt/make_light_images.py
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from renderer.io.images import write_exr, write_png
from renderer.sampling.equal_area import square_to_sphere

HERE = Path(__file__).resolve().parent


def _directions(n: int) -> np.ndarray:
    u, v = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n)
    return square_to_sphere(np.stack([u, v], -1).reshape(-1, 2).astype(np.float32)).reshape(n, n, 3)


def goniometric() -> np.ndarray:
    """Brighter towards the map's pole (+z) and towards +x, with R, G, B unequal (mean ≠ luminance)."""
    d = _directions(32)
    y = 0.2 + np.clip(d[..., 2], 0, 1) ** 2 * 1.5 + 0.6 * (d[..., 0] > 0.3)
    return np.stack([y * 1.4, y * 0.8, y * 0.8], -1).astype(np.float32)


def slide() -> np.ndarray:
    """24x16: four coloured quadrants and a white bar along the top rows, a dark left column."""
    h, w = 16, 24
    img = np.zeros((h, w, 3), np.float32)
    img[: h // 2, : w // 2] = (1.0, 0.2, 0.2)
    img[: h // 2, w // 2:] = (0.2, 1.0, 0.2)
    img[h // 2:, : w // 2] = (0.2, 0.2, 1.0)
    img[h // 2:, w // 2:] = (1.0, 1.0, 0.3)
    img[:3] = (2.0, 2.0, 2.0)
    img[:, :2] = 0.0
    return img


def environment() -> np.ndarray:
    """A bluish upper hemisphere (the map's +z) with a warm patch, a dim lower one (linear, ≤ 1)."""
    d = _directions(32)
    up = np.clip(d[..., 2], 0, 1)
    sky = np.stack([0.1 + 0.15 * up, 0.15 + 0.2 * up, 0.2 + 0.3 * up], -1)
    sky[(d[..., 0] > 0.5) & (d[..., 2] > 0.2)] = (1.0, 0.7, 0.35)
    return np.where(d[..., 2:3] > 0, sky, 0.02).astype(np.float32)


def main() -> None:
    for name, img in (("light_goniometric", goniometric()), ("light_slide", slide())):
        write_exr(HERE / f"{name}_image.exr", img)
    write_png(HERE / "light_environment_image.png", environment())


if __name__ == "__main__":
    main()
