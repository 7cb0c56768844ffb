"""Thin-film thickness map (nm) for a lens: thicker towards the rim, as coatings are, for a
superellipse or a mask outline. The map covers the outline's bounding box, u right and v down."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
from scipy import ndimage

from assets_gen.core import Generator, Job, Params, param, reading, require
from assets_gen.core.noise import smooth_noise
from assets_gen.core.output import Banded, write_map


@dataclass(frozen=True)
class LensThicknessParams(Params):
    width_mm: float = param(55.0, "lens outline width, mm")
    height_mm: float = param(45.0, "lens outline height, mm")
    superellipse_exponent: float = param(3.0, "superellipse exponent n of |x/a|^n + |y/b|^n = 1 (2 = ellipse)")
    mask: str = param("", "greyscale PNG lens outline (non-zero = lens) used instead of the superellipse",
                      path=True)
    resolution: int = param(512, "map pixels along the longer side")
    center_nm: float = param(300.0, "film thickness at the lens centre, nm")
    edge_nm: float = param(420.0, "film thickness at the outline, nm (coatings thicken at the rim)")
    profile_exponent: float = param(2.0, "thickness grows as (normalised radius)^exponent")
    noise_nm: float = param(0.0, "amplitude of smooth thickness noise, nm")
    noise_size_mm: float = param(8.0, "feature size of the thickness noise, mm")

    def validate(self) -> None:
        require(self.width_mm > 0 and self.height_mm > 0, "lens width and height must be positive (mm)")
        require(self.superellipse_exponent > 0, "superellipse exponent must be positive")
        require(8 <= self.resolution <= 16384, "resolution must be between 8 and 16384 pixels")
        require(self.center_nm >= 0 and self.edge_nm >= 0, "film thicknesses must be non-negative (nm)")
        require(self.profile_exponent > 0, "profile exponent must be positive")
        require(self.noise_nm >= 0 and self.noise_size_mm > 0, "noise amplitude >= 0 and size > 0 (nm, mm)")
        require(not self.mask or Path(self.mask).is_file(), f"lens mask {self.mask!r} not found")


def superellipse_radius(x: np.ndarray, y: np.ndarray, a: float, b: float, n: float) -> np.ndarray:
    """The superellipse 'norm' (|x/a|^n + |y/b|^n)^(1/n): 0 at the centre, 1 on the outline,
    growing along every ray from the centre."""
    return (np.abs(x / a) ** n + np.abs(y / b) ** n) ** (1.0 / n)


def mask_radius(mask: np.ndarray) -> np.ndarray:
    """A normalised radius for any outline: d_c / (d_c + d_e), with d_c the distance from the
    mask's centroid and d_e the distance to the outside. It is 0 at the centroid and 1 on the
    outline, and grows along rays from the centre for convex, centred outlines (d_e is concave)."""
    require(bool(mask.any()), "lens mask is empty")
    d_edge = ndimage.distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
    cy, cx = ndimage.center_of_mass(mask)
    yy, xx = np.indices(mask.shape)
    d_centre = np.hypot(yy - cy, xx - cx)
    with np.errstate(invalid="ignore", divide="ignore"):
        rho = d_centre / (d_centre + d_edge)
    return np.where(mask, np.nan_to_num(rho), 1.0)


def lens_thickness(p: LensThicknessParams, seed: int) -> tuple[Callable[[int, int], np.ndarray], tuple[int, int]]:
    """(rows, shape): ``rows(y0, y1)`` gives the thickness in nm of map rows y0..y1 (float64),
    which rises from centre to rim as rho^k and is zero outside the lens. Rows are made a band at
    a time, each texel exactly as a whole-map computation would, so a 16384-pixel map never holds
    its float64 intermediates whole (a mask's outline still needs its whole distance transform)."""
    rng = np.random.default_rng(seed)
    if p.mask:
        from PIL import Image
        from skimage.transform import resize

        with reading(p.mask, "lens mask"), Image.open(p.mask) as im:
            raw = np.asarray(im.convert("L"), dtype=np.float64) / 255.0
        scale = p.resolution / max(raw.shape)
        shape = (max(1, round(raw.shape[0] * scale)), max(1, round(raw.shape[1] * scale)))
        whole_mask = resize(raw, shape, order=1, anti_aliasing=True) > 0.5
        whole_rho = mask_radius(whole_mask)
        radius = lambda y0, y1: (whole_rho[y0:y1], whole_mask[y0:y1])
    else:
        w, h = (p.resolution, max(1, round(p.resolution * p.height_mm / p.width_mm))) \
            if p.width_mm >= p.height_mm else (max(1, round(p.resolution * p.width_mm / p.height_mm)), p.resolution)
        x = (np.arange(w) + 0.5) / w * p.width_mm - p.width_mm / 2
        y = (np.arange(h) + 0.5) / h * p.height_mm - p.height_mm / 2
        shape = (h, w)
        # the outline crosses the middle row wherever it covers any pixel (it is convex and centred)
        inside = superellipse_radius(x, y[np.abs(y).argmin()], p.width_mm / 2, p.height_mm / 2,
                                     p.superellipse_exponent) <= 1.0
        require(bool(inside.any()), "lens outline covers no pixel; raise --resolution")

        def radius(y0: int, y1: int) -> tuple[np.ndarray, np.ndarray]:
            rho = superellipse_radius(x[None, :], y[y0:y1, None], p.width_mm / 2, p.height_mm / 2,
                                      p.superellipse_exponent)
            return rho, rho <= 1.0
    noise = smooth_noise(rng, (0.0, 0.0), (p.height_mm, p.width_mm), p.noise_size_mm) if p.noise_nm > 0 else None

    def rows(y0: int, y1: int) -> np.ndarray:
        rho, mask = radius(y0, y1)
        t = p.center_nm + (p.edge_nm - p.center_nm) * np.clip(rho, 0.0, 1.0) ** p.profile_exponent
        if noise is not None:
            hh, ww = shape
            yy, xx = np.indices(mask.shape)
            t = t + p.noise_nm * noise((yy + y0 + 0.5) / hh * p.height_mm, (xx + 0.5) / ww * p.width_mm)
        return np.where(mask, np.maximum(t, 0.0), 0.0)

    return rows, shape


def write(job: Job) -> list[str]:
    p = job.params
    rows, shape = lens_thickness(p, job.seed)
    return write_map(job.stage, "lens_thickness", Banded(shape, rows), "nm", job.preview,
                     {"width_mm": p.width_mm, "height_mm": p.height_mm})


GENERATOR = Generator("lens-thickness", "thin-film thickness map (nm) for a lens, thicker towards the rim",
                      LensThicknessParams, write, __doc__, previews=True)
