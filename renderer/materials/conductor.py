"""pbrt's ``conductor``: a metal with complex index eta + i k (or an artist ``reflectance``),
smooth (a mirror) or rough (GGX). Two-sided.

Spectral eta and k (pbrt-v4's named spectra such as ``metal-Au-eta``, inline samples, ``.spd``
files): the Fresnel term is a table over the angle of incidence baked at upload from the
per-wavelength Fresnel reflectance, integrated at every nm of 360–830 nm against the CIE observer
under D65 (:mod:`renderer.optics.angular_table`), the convention the renderer uses for every
reflectance. The RGB projections of eta and k put into the per-channel Fresnel formula instead
are not the RGB of the reflectance (the formula is not linear): gold's red came out 6 % low
against pbrt-v4. A spectrum beside an RGB colour that is not grey (the one cannot be put at the
other's wavelengths), a texture, or an artist ``reflectance`` keep the per-channel formula."""
from __future__ import annotations

from typing import Any

import numpy as np
import warp as wp

from renderer.color.named_spectra import SpectralRGB
from renderer.color.spectral import mode_wavelengths
from renderer.errors import Location
from renderer.materials.bsdf import (BSDF, FIRST_DERIVED_FLAG, GLOSSY, REFLECTION, SPECULAR, BSDFEval, BSDFSample,
                                     delta_sample, failed_sample, reflect_z, same_hemisphere, sampled, signed_z)
from renderer.materials.energy import MEAN_NODES, mirror_lost, mirror_multiple
from renderer.materials.microfacet import (ROUGHNESS_PARAMS, ggx_D, ggx_G, ggx_sample_visible, ggx_visible_pdf,
                                           is_smooth, resolve_roughness, roughness_to_alpha)
from renderer.optics.angular_table import conductor_table, table_locate, table_value
from renderer.optics.fresnel import fresnel_conductor
from renderer.parameters import Parameter, Parameters, TextureRef
from renderer.sampling.warps import cosine_hemisphere
from renderer.vecmath import INV_PI

NAME = "conductor"

# pbrt-v4's default conductor is copper; these are copper's eta and k averaged over the
# sRGB primaries' wavelength bands (the values pbrt-v3 and Mitsuba use for "Cu").
COPPER_ETA = (0.200438, 0.924033, 1.102212)
COPPER_K = (3.912949, 2.452848, 2.142188)

PARAMS = Parameters(
    Parameter("eta", "rgb", COPPER_ETA, 0.0, texture=True, doc="real part of the complex index (default: copper)"),
    Parameter("k", "rgb", COPPER_K, 0.0, texture=True, doc="imaginary part of the complex index (default: copper)"),
    *ROUGHNESS_PARAMS,
    Parameter("reflectance", "rgb", None, 0.0, 0.9999, texture=True,
              doc="artist reflectance at normal incidence; replaces eta and k when given"),
    Parameter("multiscatter", "bool", False, doc="count the bounces between microfacets (energy compensation, "
              "docs/materials.md); off: pbrt-v4's single scattering"),
)
SLOT = PARAMS.slots
FLAG = PARAMS.flags
#: Derived flag: ``reflectance`` was given, so it replaces eta and k.
ARTIST = wp.constant(FIRST_DERIVED_FLAG)


def resolve(values: dict[str, Any], loc: Location | None) -> tuple[dict[str, Any], int]:
    return resolve_roughness(values), ARTIST if "reflectance" in values else 0


def _on_grid(v: Any, lam: np.ndarray) -> np.ndarray | None:
    """A parameter's value at every wavelength of lam: its spectrum, or its grey constant; None
    for a texture or a colour that is not grey."""
    if isinstance(v, SpectralRGB):
        return v.on_grid(lam)
    rgb = np.asarray(v, np.float64)
    return np.full(lam.shape, rgb[0]) if np.all(rgb == rgb[0]) else None


def spectral_fresnel_rows(eta: Any, k: Any, outside: float = 1.0) -> tuple[np.ndarray, str]:
    """The spectral Fresnel table of a conductor of index (eta + i k) / outside where eta or k is a
    spectrum (see the module docstring); no rows otherwise. ``outside``: the index of the medium
    it borders (coatedconductor's coat)."""
    if not (isinstance(eta, SpectralRGB) or isinstance(k, SpectralRGB)):
        return np.zeros((0, 4), np.float32), ""
    if isinstance(eta, TextureRef) or isinstance(k, TextureRef):
        return np.zeros((0, 4), np.float32), ""
    lam = mode_wavelengths("reference")[0]
    eta_l, k_l = _on_grid(eta, lam), _on_grid(k, lam)
    if eta_l is None or k_l is None:
        return np.zeros((0, 4), np.float32), ('a spectrum beside a non-grey RGB colour (eta, k) '
                                              'keeps the per-channel Fresnel of their RGB projections')
    return conductor_table(eta_l / outside, k_l / outside), ""


def table_rows(values: dict[str, Any], loc: Location | None, thin_film: str) -> tuple[np.ndarray, str]:
    """The spectral Fresnel table of a conductor whose eta or k is a spectrum. The thin-film mode
    does not matter: a table is exact here."""
    if "reflectance" in values:
        return np.zeros((0, 4), np.float32), ""
    rows, warning = spectral_fresnel_rows(PARAMS.value(values, "eta"), PARAMS.value(values, "k"))
    return rows, f"conductor: {warning}" if warning else ""


@wp.func
def conductor_fresnel(cos_i: float, eta: wp.vec3, k: wp.vec3, rows: wp.array(dtype=wp.vec4), table: int) -> wp.vec3:
    """RGB Fresnel reflectance: the baked spectral table at rows[table] when table > 0, else per channel."""
    if table > 0:
        return table_value(rows, table, 1, 0, table_locate(rows, table, cos_i))
    return fresnel_conductor(cos_i, eta, k)


@wp.func
def _alpha(b: BSDF) -> wp.vec2:
    return roughness_to_alpha(wp.vec2(b.p[SLOT.uroughness][0], b.p[SLOT.vroughness][0]),
                              (b.flags & FLAG.remaproughness) != 0)


@wp.func
def artist_k(r: wp.vec3) -> wp.vec3:
    """pbrt-v4: an artist reflectance r at normal incidence maps to eta = 1, k = 2 sqrt(r) / sqrt(1 - r)."""
    return wp.vec3(2.0 * wp.sqrt(r[0]) / wp.sqrt(1.0 - r[0]), 2.0 * wp.sqrt(r[1]) / wp.sqrt(1.0 - r[1]),
                   2.0 * wp.sqrt(r[2]) / wp.sqrt(1.0 - r[2]))


@wp.func
def conductor_eval(eta: wp.vec3, k: wp.vec3, alpha: wp.vec2, wo: wp.vec3, wi: wp.vec3,
                   rows: wp.array(dtype=wp.vec4), table: int) -> BSDFEval:
    """The rough conductor lobe (two-sided) of complex relative index eta + i k (or the spectral
    Fresnel table at rows[table], table > 0)."""
    ev = BSDFEval()
    if is_smooth(alpha) or not same_hemisphere(wo, wi):
        return ev
    sgn = wp.where(wo[2] < 0.0, -1.0, 1.0)
    o = signed_z(wo, sgn)
    i = signed_z(wi, sgn)
    wm = wp.normalize(o + i)
    g = ggx_D(wm, alpha) * ggx_G(o, i, alpha) / (4.0 * o[2] * i[2])
    ev.f = conductor_fresnel(wp.dot(o, wm), eta, k, rows, table) * g
    ev.pdf = ggx_visible_pdf(o, wm, alpha) / (4.0 * wp.abs(wp.dot(o, wm)))
    return ev


@wp.func
def mirror_sample(eta: wp.vec3, k: wp.vec3, wo: wp.vec3, rows: wp.array(dtype=wp.vec4), table: int) -> BSDFSample:
    """The smooth conductor's delta reflection."""
    return delta_sample(reflect_z(wo), conductor_fresnel(wo[2], eta, k, rows, table), 1.0, REFLECTION | SPECULAR)


@wp.func
def conductor_sample(eta: wp.vec3, k: wp.vec3, alpha: wp.vec2, wo: wp.vec3, u: wp.vec3,
                     rows: wp.array(dtype=wp.vec4), table: int) -> BSDFSample:
    """A mirror direction (smooth) or a GGX visible-normal reflection (rough)."""
    if is_smooth(alpha):
        return mirror_sample(eta, k, wo, rows, table)
    wi = reflected(wo, alpha, u, 0.0)
    if wi[2] == 0.0:
        return failed_sample()
    return sampled(wo, wi, conductor_eval(eta, k, alpha, wo, wi, rows, table), GLOSSY)


@wp.func
def reflected(wo: wp.vec3, alpha: wp.vec2, u: wp.vec3, p_cosine: float) -> wp.vec3:
    """A direction on wo's side (two-sided): cosine distributed when u[2] < p_cosine, else reflected
    about a GGX visible normal; 0 when that reflection falls below the surface."""
    sgn = wp.where(wo[2] < 0.0, -1.0, 1.0)
    o = signed_z(wo, sgn)
    i = wp.vec3(0.0)
    if u[2] < p_cosine:
        i = cosine_hemisphere(wp.vec2(u[0], u[1]))
    else:
        wm = ggx_sample_visible(o, alpha, wp.vec2(u[0], u[1]))
        i = wm * (2.0 * wp.dot(o, wm)) - o
        if i[2] <= 0.0:
            return wp.vec3(0.0)
    return signed_z(i, sgn)


@wp.func
def fresnel_mean(eta: wp.vec3, k: wp.vec3, rows: wp.array(dtype=wp.vec4), table: int) -> wp.vec3:
    """F̄ = 2∫F(μ) μ dμ per channel (midpoint rule in μ²): what the compensation lobe reflects per bounce."""
    acc = wp.vec3(0.0)
    for j in range(MEAN_NODES):
        acc += conductor_fresnel(wp.sqrt((float(j) + 0.5) / float(MEAN_NODES)), eta, k, rows, table)
    return acc / float(MEAN_NODES)


@wp.func
def conductor_ms_eval(eta: wp.vec3, k: wp.vec3, alpha: wp.vec2, wo: wp.vec3, wi: wp.vec3,
                      rows: wp.array(dtype=wp.vec4), table: int) -> BSDFEval:
    """Single scattering plus Kulla–Conty's lobe (:mod:`.energy`); its density mixes the visible-normal
    reflection with a cosine lobe chosen with probability 1 − E(μo), as ``conductor_ms_sample`` draws."""
    ev = conductor_eval(eta, k, alpha, wo, wi, rows, table)
    if is_smooth(alpha) or not same_hemisphere(wo, wi):
        return ev
    mu_o = wp.abs(wo[2])
    mu_i = wp.abs(wi[2])
    p_ms = mirror_lost(rows, alpha, mu_o)
    ev.f = ev.f + mirror_multiple(rows, alpha, mu_o, mu_i, fresnel_mean(eta, k, rows, table))
    ev.pdf = (1.0 - p_ms) * ev.pdf + p_ms * mu_i * INV_PI
    return ev


@wp.func
def conductor_ms_sample(eta: wp.vec3, k: wp.vec3, alpha: wp.vec2, wo: wp.vec3, u: wp.vec3,
                        rows: wp.array(dtype=wp.vec4), table: int) -> BSDFSample:
    """The visible-normal reflection or, with probability 1 − E(μo), a cosine-distributed direction;
    weighted by the whole of ``conductor_ms_eval``."""
    if is_smooth(alpha):
        return conductor_sample(eta, k, alpha, wo, u, rows, table)
    wi = reflected(wo, alpha, u, mirror_lost(rows, alpha, wp.abs(wo[2])))
    if wi[2] == 0.0:
        return failed_sample()
    return sampled(wo, wi, conductor_ms_eval(eta, k, alpha, wo, wi, rows, table), GLOSSY)


@wp.func
def _eta(b: BSDF) -> wp.vec3:
    return wp.where((b.flags & ARTIST) != 0, wp.vec3(1.0), b.p[SLOT.eta])


@wp.func
def _k(b: BSDF) -> wp.vec3:
    if (b.flags & ARTIST) != 0:
        return artist_k(b.p[SLOT.reflectance])
    return b.p[SLOT.k]


@wp.func
def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    if (b.flags & FLAG.multiscatter) != 0:
        return conductor_ms_eval(_eta(b), _k(b), _alpha(b), wo, wi, b.layers, b.table_first)
    return conductor_eval(_eta(b), _k(b), _alpha(b), wo, wi, b.layers, b.table_first)


@wp.func
def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    if (b.flags & FLAG.multiscatter) != 0:
        return conductor_ms_sample(_eta(b), _k(b), _alpha(b), wo, u, b.layers, b.table_first)
    return conductor_sample(_eta(b), _k(b), _alpha(b), wo, u, b.layers, b.table_first)


# Kernels compile only the lobes their scene's conductors can reach (renderer.materials.hooks):
# the functions above handle every case and are what the tests and other materials call.


@wp.func
def single_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    """``eval_pdf`` where no conductor counts the bounces between microfacets."""
    return conductor_eval(_eta(b), _k(b), _alpha(b), wo, wi, b.layers, b.table_first)


@wp.func
def single_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    """``sample`` where no conductor counts the bounces between microfacets."""
    return conductor_sample(_eta(b), _k(b), _alpha(b), wo, u, b.layers, b.table_first)


@wp.func
def smooth_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    """``eval_pdf`` where every conductor is a mirror: a delta lobe, no value anywhere."""
    return BSDFEval()


@wp.func
def smooth_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    """``sample`` where every conductor is a mirror."""
    return mirror_sample(_eta(b), _k(b), wo, b.layers, b.table_first)


#: The lobes of a kernel where every conductor is smooth, and where none counts the bounces between
#: microfacets (picked by :func:`renderer.materials.hooks`).
SMOOTH_LOBES = (smooth_eval_pdf, smooth_sample)
SINGLE_LOBES = (single_eval_pdf, single_sample)
