"""Thin-film thickness map (nm) for a lens: thicker towards the rim, as coatings are, for a
superellipse or a mask outline. The map covers the outline's bounding box, u right and v down."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import ndimage

from assets_gen.core import Generator, Job, Params, param, reading, require
from assets_gen.core.noise import smooth_noise
from assets_gen.core.output import write_map


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


def lens_thickness(p: LensThicknessParams, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(thickness in nm, lens mask): thickness rises from centre to rim as rho^k; zero outside."""
    rng = np.random.default_rng(seed)
    if p.mask:
        from PIL import Image
        from skimage.transform import resize

        with reading(p.mask, "lens mask"), Image.open(p.mask) as im:
            raw = np.asarray(im.convert("L"), dtype=np.float64) / 255.0
        scale = p.resolution / max(raw.shape)
        shape = (max(1, round(raw.shape[0] * scale)), max(1, round(raw.shape[1] * scale)))
        mask = resize(raw, shape, order=1, anti_aliasing=True) > 0.5
        rho = mask_radius(mask)
    else:
        w, h = (p.resolution, max(1, round(p.resolution * p.height_mm / p.width_mm))) \
            if p.width_mm >= p.height_mm else (max(1, round(p.resolution * p.width_mm / p.height_mm)), p.resolution)
        x = (np.arange(w) + 0.5) / w * p.width_mm - p.width_mm / 2
        y = (np.arange(h) + 0.5) / h * p.height_mm - p.height_mm / 2
        rho = superellipse_radius(x[None, :], y[:, None], p.width_mm / 2, p.height_mm / 2,
                                  p.superellipse_exponent)
        mask = rho <= 1.0
        require(bool(mask.any()), "lens outline covers no pixel; raise --resolution")
    t = p.center_nm + (p.edge_nm - p.center_nm) * np.clip(rho, 0.0, 1.0) ** p.profile_exponent
    if p.noise_nm > 0:
        hh, ww = mask.shape
        noise = smooth_noise(rng, (0.0, 0.0), (p.height_mm, p.width_mm), p.noise_size_mm)
        yy, xx = np.indices(mask.shape)
        t = t + p.noise_nm * noise((yy + 0.5) / hh * p.height_mm, (xx + 0.5) / ww * p.width_mm)
    return np.where(mask, np.maximum(t, 0.0), 0.0), mask


def write(job: Job) -> list[str]:
    p = job.params
    return write_map(job.stage, "lens_thickness", lens_thickness(p, job.seed)[0], "nm", job.preview,
                     {"width_mm": p.width_mm, "height_mm": p.height_mm})


GENERATOR = Generator("lens-thickness", "thin-film thickness map (nm) for a lens, thicker towards the rim",
                      LensThicknessParams, write, __doc__, previews=True)
