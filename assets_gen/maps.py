"""Scalar maps in physical units: lens film thickness (nm), shell growth-band height and fine
ridge bump (m), plus the pieces the terrain generators share (band-limited noise, greyscale
previews, parameter dataclasses as CLI options, staged output with a manifest).

Shell maps live in the shell's parameter square, the UVs `assets-gen seashell` writes: u runs
along growth from the apex (u = 0) to the margin (u = 1), v across the shell (around the aperture,
or across the fan of a scallop), so growth bands and concentric ridges are lines of constant u and
radial ribs lines of constant v.
Lens maps cover the lens outline's bounding box, u to the right and v down, like the image.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
from scipy import ndimage

from assets_gen.common import require, staged_output, write_manifest

# --------------------------------------------------------------------------------------------
# Shared by the terrain generators
# --------------------------------------------------------------------------------------------

#: Mean variance of a random lattice smoothed by a cubic B-spline, per axis (integral of B^2).
_BSPLINE_VARIANCE = 151.0 / 315.0


def smooth_noise(rng: np.random.Generator, lo: tuple[float, float], hi: tuple[float, float],
                 feature_size: float) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """Zero-mean, roughly unit-variance noise with features about ``feature_size`` across over the
    box [lo, hi]. It is a cubic B-spline through a random lattice, so it can be evaluated at any
    point: a mesh vertex and a map texel at the same place read the same value whatever the
    sampling resolution (ripples as geometry and as a map then agree)."""
    shape = tuple(int(math.ceil((h - l) / feature_size)) + 4 for l, h in zip(lo, hi))
    lattice = rng.standard_normal(shape) / _BSPLINE_VARIANCE

    def field_at(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
        coords = np.stack([(a - lo[0]) / feature_size + 1.5, (b - lo[1]) / feature_size + 1.5])
        out = ndimage.map_coordinates(lattice, coords.reshape(2, -1), order=3, prefilter=False,
                                      mode="nearest")
        return out.reshape(a.shape)

    return field_at


def write_preview(path: Path, values: np.ndarray, max_side: int = 512) -> None:
    """An 8-bit greyscale PNG of a map, stretched to its own range and shrunk to ``max_side``:
    for looking at, not for rendering (the EXR holds the physical values)."""
    from PIL import Image

    v = np.asarray(values, dtype=np.float64)
    lo, hi = float(np.nanmin(v)), float(np.nanmax(v))
    grey = np.zeros_like(v) if hi <= lo else (v - lo) / (hi - lo)
    step = max(1, int(math.ceil(max(v.shape) / max_side)))
    img = (np.nan_to_num(grey[::step, ::step]) * 255.0 + 0.5).astype(np.uint8)
    Image.fromarray(img).save(path, format="PNG", optimize=False)


def param(default: Any, help: str, **kw: Any) -> Any:
    """A dataclass field that is also a CLI option: ``help`` should name the unit."""
    return field(default=default, metadata={"help": help, **kw})


def add_param_arguments(parser: argparse.ArgumentParser, cls: type) -> None:
    """One ``--option`` per field of the parameter dataclass ``cls``, defaults and units from it."""
    for f in dataclasses.fields(cls):
        flag = "--" + f.name.replace("_", "-")
        kw: dict[str, Any] = {"default": f.default, "help": f.metadata["help"], "dest": f.name}
        if "choices" in f.metadata:
            kw["choices"] = f.metadata["choices"]
        if isinstance(f.default, bool):
            kw["action"] = argparse.BooleanOptionalAction
        elif isinstance(f.default, tuple):
            kw.update(nargs=len(f.default), type=float, metavar=tuple("XYZW"[:len(f.default)]))
        else:
            kw["type"] = f.metadata.get("type", type(f.default))
        parser.add_argument(flag, **kw)


def params_from_args(args: argparse.Namespace, cls: type) -> Any:
    """The parameter dataclass from parsed options (lists from ``nargs`` become tuples)."""
    values = {f.name: getattr(args, f.name) for f in dataclasses.fields(cls)}
    return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in values.items()})


def add_generator_parser(subparsers: Any, name: str, doc: str, cls: type,
                         run: Callable[[argparse.Namespace], list[str]]) -> argparse.ArgumentParser:
    """The subcommand every terrain generator has: its parameters, ``--seed``, ``--out``, ``--preview``."""
    summary = " ".join(doc.split("\n\n")[0].split()).split(". ")[0]
    p = subparsers.add_parser(name, help=summary, description=doc,
                              formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    add_param_arguments(p, cls)
    p.add_argument("--seed", type=int, default=0, help="random seed; the same seed gives the same bytes")
    p.add_argument("--out", type=Path, default=Path("assets") / name, help="output folder")
    p.add_argument("--preview", action=argparse.BooleanOptionalAction, default=True,
                   help="also write a small PNG preview")
    p.set_defaults(run=run)
    return p


def emit(out_dir: Path, generator: str, params: Any, seed: int,
         build: Callable[[Path], list[str]]) -> list[str]:
    """Run ``build(stage)`` (it returns the names it wrote), add ``<generator>.json``, and move it all
    into ``out_dir`` only on success. Parameters are validated before anything touches the disk,
    and an output folder this call created is removed again if generation fails."""
    params.validate()
    out_dir = Path(out_dir)
    created = not out_dir.exists()
    try:
        with staged_output(out_dir) as stage:
            names = build(stage)
            manifest = f"{generator}.json"
            write_manifest(stage / manifest, generator, dataclasses.asdict(params), seed, names)
    except BaseException:
        if created and out_dir.is_dir() and not any(out_dir.iterdir()):
            out_dir.rmdir()
        raise
    return [str(out_dir / n) for n in [*names, manifest]]


def write_map(stage: Path, name: str, values: np.ndarray, units: str, preview: bool,
              header: dict[str, object] | None = None) -> list[str]:
    """``name.exr`` (one float channel ``Y`` in ``units``) and optionally ``name.png``."""
    from renderer.io.images import write_exr

    write_exr(stage / f"{name}.exr", {"Y": np.asarray(values, dtype=np.float32)},
              {"units": units, **(header or {})})
    if not preview:
        return [f"{name}.exr"]
    write_preview(stage / f"{name}.png", values)
    return [f"{name}.exr", f"{name}.png"]


# --------------------------------------------------------------------------------------------
# Lens film thickness
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class LensThicknessParams:
    width_mm: float = param(55.0, "lens outline width, mm")
    height_mm: float = param(45.0, "lens outline height, mm")
    superellipse_exponent: float = param(3.0, "superellipse exponent n of |x/a|^n + |y/b|^n = 1 (2 = ellipse)")
    mask: str = param("", "greyscale PNG lens outline (non-zero = lens) used instead of the superellipse",
                      type=str)
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

        with Image.open(p.mask) as im:
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


# --------------------------------------------------------------------------------------------
# Shell height (growth bands) and bump (fine ridges)
# --------------------------------------------------------------------------------------------

def banded_phase(t: np.ndarray, count: int, irregularity: float,
                 rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(phase in [0, 1) within its band, band index) for positions t in [0, 1] cut into ``count``
    bands whose widths vary by ``irregularity`` (gamma-distributed, like growth increments that
    follow the seasons: 0 gives equal bands)."""
    if irregularity > 0:
        k = 1.0 / irregularity ** 2
        widths = rng.gamma(k, 1.0 / k, size=count)
    else:
        widths = np.ones(count)
    edges = np.concatenate([[0.0], np.cumsum(widths) / widths.sum()])
    idx = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, count - 1)
    phase = (t - edges[idx]) / (edges[idx + 1] - edges[idx])
    return np.clip(phase, 0.0, 1.0 - 1e-12), idx


@dataclass(frozen=True)
class ShellMapParams:
    width: int = param(1024, "map pixels along u (apex to margin)")
    height: int = param(1024, "map pixels along v (across the shell)")
    waviness: float = param(0.01, "how far band and ridge lines wander, as a fraction of the map")
    waviness_size: float = param(0.1, "feature size of the wander, as a fraction of the map")

    def validate(self) -> None:
        require(8 <= self.width <= 16384 and 8 <= self.height <= 16384, "map size must be 8..16384 pixels")
        require(0 <= self.waviness <= 0.2, "waviness must be between 0 and 0.2")
        require(self.waviness_size > 0, "waviness size must be positive")


@dataclass(frozen=True)
class ShellHeightParams(ShellMapParams):
    bands: int = param(14, "growth bands from apex to margin")
    band_height_mm: float = param(0.3, "shell thickening across one growth band, mm")
    irregularity: float = param(0.35, "relative spread of band widths and heights (0 = regular)")

    def validate(self) -> None:
        super().validate()
        require(self.bands >= 1, "need at least one growth band")
        require(self.band_height_mm >= 0, "band height must be non-negative (mm)")
        require(0 <= self.irregularity <= 2, "irregularity must be between 0 and 2")


@dataclass(frozen=True)
class ShellBumpParams(ShellMapParams):
    pattern: str = param("radial", "ridges along the growth direction (radial ribs) or across it "
                         "(concentric growth lines)", choices=("radial", "concentric"))
    ridges: int = param(60, "number of ridges across the map")
    ridge_height_mm: float = param(0.05, "ridge height, mm")
    sharpness: float = param(4.0, "ridge profile exponent: 1 rounded, larger = narrow crests")

    def validate(self) -> None:
        super().validate()
        require(self.ridges >= 1, "need at least one ridge")
        require(self.ridge_height_mm >= 0, "ridge height must be non-negative (mm)")
        require(self.sharpness >= 1, "sharpness must be at least 1")


def _shell_grid(p: ShellMapParams, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) texel centres, each coordinate wandered by smooth noise so lines are not ruled."""
    u = (np.arange(p.width) + 0.5) / p.width
    v = (np.arange(p.height) + 0.5) / p.height
    uu, vv = np.meshgrid(u, v)
    wander_u = smooth_noise(rng, (0.0, 0.0), (1.0, 1.0), p.waviness_size)
    wander_v = smooth_noise(rng, (0.0, 0.0), (1.0, 1.0), p.waviness_size)
    return (np.clip(uu + p.waviness * wander_u(uu, vv), 0, 1),
            np.clip(vv + p.waviness * wander_v(uu, vv), 0, 1))


def shell_height(p: ShellHeightParams, seed: int) -> np.ndarray:
    """Height (m) of growth bands: the shell swells across each band and thins again at the growth
    check that ends it; band heights vary like the widths (a good and a poor season)."""
    rng = np.random.default_rng(seed)
    u, _ = _shell_grid(p, rng)
    phase, idx = banded_phase(u, p.bands, p.irregularity, rng)
    amp = p.band_height_mm * 1e-3 * rng.lognormal(0.0, p.irregularity * 0.5, size=p.bands)
    return amp[idx] * np.sin(np.pi * phase) ** 2


def shell_bump(p: ShellBumpParams, seed: int) -> np.ndarray:
    """Height (m) of fine regular ridges: |cos|^sharpness peaks, radial (constant v) or concentric
    (constant u)."""
    rng = np.random.default_rng(seed)
    u, v = _shell_grid(p, rng)
    t = v if p.pattern == "radial" else u
    phase, _ = banded_phase(t, p.ridges, 0.0, rng)
    return p.ridge_height_mm * 1e-3 * np.sin(np.pi * phase) ** p.sharpness


# --------------------------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------------------------

def _runner(name: str, cls: type, make: Callable[[Any, int], np.ndarray], units: str,
            extra_header: Callable[[Any], dict[str, object]]) -> Callable[[argparse.Namespace], list[str]]:
    def run(args: argparse.Namespace) -> list[str]:
        p = params_from_args(args, cls)

        def build(stage: Path) -> list[str]:
            values = make(p, args.seed)
            return write_map(stage, name.replace("-", "_"), values, units, args.preview, extra_header(p))

        return emit(args.out, name, p, args.seed, build)
    return run


def register(subparsers: Any) -> None:
    add_generator_parser(
        subparsers, "lens-thickness",
        "Thin-film thickness map (nm) for a lens: thicker towards the rim, for a superellipse or "
        "a mask outline.", LensThicknessParams,
        _runner("lens-thickness", LensThicknessParams, lambda p, s: lens_thickness(p, s)[0], "nm",
                lambda p: {"width_mm": p.width_mm, "height_mm": p.height_mm}))
    add_generator_parser(
        subparsers, "shell-height",
        "Shell height map (m) of growth bands in the shell's (u apex-to-margin, v across) square.",
        ShellHeightParams, _runner("shell-height", ShellHeightParams, shell_height, "m", lambda p: {}))
    add_generator_parser(
        subparsers, "shell-bump",
        "Shell bump map (m) of fine radial ribs or concentric ridges in the shell's (u, v) square.",
        ShellBumpParams, _runner("shell-bump", ShellBumpParams, shell_bump, "m", lambda p: {}))

