"""Dispersion: a dielectric whose index varies with the wavelength (pbrt-v4's ``glass-*`` named
spectra, inline samples, ``.spd`` files) refracts each wavelength its own way.

pbrt-v4 terminates a path's secondary wavelengths at such an interface and goes on with the hero
wavelength's index. This renderer carries RGB, so a path picks one wavelength λ at its first
dispersive interface, from the bounce's own sampler dimension (``WAVELENGTH``, docs/samplers.md),
with pbrt-v4's visible-wavelength density p(λ) ∝ sech²(0.0072 (λ − 538)) over 360–830 nm. Its RGB
throughput is multiplied by w(λ) / p(λ), where w is the thin film's colour-matching table
(:func:`renderer.color.spectral.rgb_weight_table`: CIE 1931 under D65 to linear sRGB, ∫ w = (1, 1, 1),
so a flat spectrum stays white on average), and from then on every dispersive interface uses
eta(λ). The estimate is exact where what the path meets before and after is grey; a coloured
surface on such a path is multiplied by its RGB rather than at λ. w has negative channels (a
single wavelength lies outside the sRGB gamut), so such a path's sample may be negative in a
channel: the mean converges to the image, as in pbrt's own film.

Device layout of a material's eta(λ) in the scene's layer table: a header (first λ, step, node
count, 0), then one row (eta, 0, 0, 0) per node of a uniform grid over 360–830 nm.
"""
from __future__ import annotations

import numpy as np
import warp as wp

from renderer.color.named_spectra import SpectralFloat
from renderer.color.rgb_weights import RgbWeightTable, rgb_weight
from renderer.color.spectral import LAMBDA_MAX_NM, LAMBDA_MIN_NM

#: Node spacing of eta(λ): the colour tables' 1 nm (at 5 nm, linear interpolation of F11 is
#: 9e-5 off its curve below 450 nm; 471 rows cost nothing).
STEP_NM = 1.0


def is_dispersive(eta: object) -> bool:
    """Whether a dielectric's eta was read from a spectrum that is not constant over 360–830 nm."""
    if not isinstance(eta, SpectralFloat):
        return False
    v = eta.on_grid(np.arange(LAMBDA_MIN_NM, LAMBDA_MAX_NM + 1.0))
    return bool(np.ptp(v) > 0.0)


def eta_rows(eta: SpectralFloat) -> np.ndarray:
    """The device rows of eta(λ) (see the module docstring)."""
    lam = np.arange(LAMBDA_MIN_NM, LAMBDA_MAX_NM + 0.5 * STEP_NM, STEP_NM)
    rows = np.zeros((1 + len(lam), 4), np.float32)
    rows[0, :3] = (LAMBDA_MIN_NM, STEP_NM, len(lam))
    rows[1:, 0] = eta.on_grid(lam)
    return rows


@wp.func
def eta_at(rows: wp.array(dtype=wp.vec4), first: int, lambda_nm: float) -> float:
    """eta at lambda_nm from the rows at rows[first], linearly interpolated (clamped at the ends)."""
    head = rows[first]
    n = int(head[2])
    x = wp.clamp((lambda_nm - head[0]) / head[1], 0.0, float(n - 1))
    j = wp.min(int(wp.floor(x)), n - 2)
    t = x - float(j)
    return (1.0 - t) * rows[first + 1 + j][0] + t * rows[first + 2 + j][0]


@wp.func
def sample_wavelength(u: float) -> wp.vec2:
    """(λ in nm, its density per nm) from pbrt-v4's visible-wavelength distribution, by inversion
    of its closed-form CDF on [360, 830]."""
    x = 0.85691062 - 1.82750197 * u
    lam = 538.0 - 138.888889 * 0.5 * wp.log((1.0 + x) / (1.0 - x))
    c = wp.cosh(0.0072 * (lam - 538.0))
    return wp.vec2(lam, 0.0039398042 / (c * c))


@wp.func
def wavelength_weight(table: RgbWeightTable, sample: wp.vec2) -> wp.vec3:
    """The RGB factor w(λ) / p(λ) of a sampled wavelength (sample_wavelength's (λ, p))."""
    return rgb_weight(table, sample[0]) / sample[1]
