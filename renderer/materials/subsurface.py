"""pbrt-v4's ``subsurface`` material: a dielectric boundary (``eta``, smooth or GGX-rough) around a
homogeneous scattering body whose light transport is pbrt-v4's tabulated photon-beam-diffusion
BSSRDF (:mod:`.beam_diffusion`, :mod:`.tabulated_bssrdf`).

The body's coefficients come, as in pbrt-v4, from exactly one of:

1. ``name``: a measured medium (Jensen et al. 2001; Narasimhan et al. 2006), sigma_s' and sigma_a in
   mm^-1 read as per scene unit; g is forced to 0 (the data are reduced scattering coefficients);
2. ``sigma_a`` and ``sigma_s`` (both, or neither);
3. ``reflectance`` (the body's effective albedo) with ``mfp`` (mean free path, default 1): the
   albedo comes from inverting the table's rho_eff, sigma_t = 1 / mfp;
4. nothing: pbrt-v4's defaults (whole milk's coefficients).

``scale`` multiplies sigma_a and sigma_s (and mfp). What pbrt-v4 does not read in the chosen mode
(``sigma_a`` with a ``name``, ``mfp`` without ``reflectance``, ...) is refused, as pbrt-v4 refuses an
unused parameter; so is an unknown ``name`` and ``sigma_a`` without ``sigma_s`` or the reverse.

The BSDF at a hit is pbrt-v4's DielectricBxDF. The integrator's subsurface step
(:mod:`renderer.integrators.subsurface`) splits it: light transmitted into the body goes through
the BSSRDF to an exit point found by probe rays, where the BSDF becomes the exit lobe Sw
(pbrt-v4's NormalizedFresnelBxDF, flag EXIT); otherwise the vertex keeps only the reflection
(flag SURFACE). Without either flag (the AOV kernel) the material is the whole dielectric.

An extension (pbrt-v4 has none): a thin film or multilayer stack on the boundary, given by
``thickness`` (nm) and ``eta_film`` or by ``thinfilm``'s stack parameters (``layer_eta``, ...):
its R and T replace the dielectric's F and 1 − F where light enters and where it leaves
(:mod:`.film_body`, flag FILM).
"""
from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np
import warp as wp

from renderer.color import rgb_spectrum
from renderer.errors import Location, SceneError, UnsupportedError
from renderer.materials.beam_diffusion import fresnel_moment1, table_rows as profile_rows
from renderer.materials.bsdf import BSDF, FIRST_DERIVED_FLAG, REFLECTION, TRANSMISSION, BSDFEval, BSDFSample
from renderer.materials.dielectric import dielectric_eval, dielectric_sample
from renderer.materials.film_body import (FILM_PARAMS, body_coating, exit_direction, film_boundary_eval,
                                          film_boundary_sample, film_exit_eval, film_exit_sample, has_film, resolve_film)
from renderer.materials.coating import Coating
from renderer.materials.stack import stack_rows
from renderer.materials.microfacet import ROUGHNESS_PARAMS, resolve_roughness, roughness_to_alpha
from renderer.optics.fresnel import fresnel_dielectric
from renderer.parameters import Parameter, Parameters, TextureRef
from renderer.vecmath import INV_PI

NAME = "subsurface"
#: pbrt-v4's default coefficients (mm^-1): whole milk.
DEFAULT_SIGMA_A = (0.0011, 0.0024, 0.014)
DEFAULT_SIGMA_S = (2.55, 3.21, 3.77)
PARAMS = Parameters(
    Parameter("name", "string", None, doc="a measured medium (pbrt-v4's names, below); forces g = 0"),
    Parameter("sigma_a", "rgb", DEFAULT_SIGMA_A, 0.0, texture=True,
              doc="absorption coefficient per unit length, given with sigma_s (default: whole milk's, in mm^-1)"),
    Parameter("sigma_s", "rgb", DEFAULT_SIGMA_S, 0.0, texture=True,
              doc="scattering coefficient per unit length, given with sigma_a (default: whole milk's)"),
    Parameter("reflectance", "rgb", None, 0.0, 1.0, texture=True,
              doc="effective albedo of the body, instead of the coefficients"),
    Parameter("mfp", "rgb", 1.0, 0.0, texture=True, doc="with reflectance: mean free path 1 / sigma_t"),
    Parameter("scale", "float", 1.0, 0.0, doc="multiplies sigma_a and sigma_s (and mfp)"),
    Parameter("eta", "float", 1.33, 1.0e-3, doc="index of refraction of the body"),
    Parameter("g", "float", 0.0, -1.0, 1.0, doc="Henyey–Greenstein asymmetry of the body's scattering"),
    *ROUGHNESS_PARAMS,
    *FILM_PARAMS,
)
SLOT = PARAMS.slots
FLAG = PARAMS.flags
#: Derived flags: the coefficients come from reflectance and mfp; the subsurface step's exit point
#: (only the exit lobe); its surface route (only the reflection).
FROM_REFLECTANCE = wp.constant(FIRST_DERIVED_FLAG)
EXIT = wp.constant(FIRST_DERIVED_FLAG << 1)
SURFACE = wp.constant(FIRST_DERIVED_FLAG << 2)
#: The body's coefficients are constant colours: the step evaluates them per wavelength (``spectra``).
SPECTRAL = wp.constant(FIRST_DERIVED_FLAG << 3)
#: A film or stack coats the boundary (:mod:`.film_body`).
FILM = wp.constant(FIRST_DERIVED_FLAG << 4)

#: pbrt-v4's named media: (sigma_s', sigma_a) in mm^-1, RGB. Jensen, Marschner, Levoy and Hanrahan,
#: "A Practical Model for Subsurface Light Transport" (SIGGRAPH 2001), Table 2; then Narasimhan,
#: Gupta, Donner, Ramamoorthi, Nayar and Jensen, "Acquiring Scattering Properties of Participating
#: Media by Dilution" (SIGGRAPH 2006), as pbrt-v4's GetMediumScatteringProperties lists them.
NAMED_MEDIA: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "Apple": ((2.29, 2.39, 1.97), (0.0030, 0.0034, 0.046)),
    "Chicken1": ((0.15, 0.21, 0.38), (0.015, 0.077, 0.19)),
    "Chicken2": ((0.19, 0.25, 0.32), (0.018, 0.088, 0.20)),
    "Cream": ((7.38, 5.47, 3.15), (0.0002, 0.0028, 0.0163)),
    "Ketchup": ((0.18, 0.07, 0.03), (0.061, 0.97, 1.45)),
    "Marble": ((2.19, 2.62, 3.00), (0.0021, 0.0041, 0.0071)),
    "Potato": ((0.68, 0.70, 0.55), (0.0024, 0.0090, 0.12)),
    "Skimmilk": ((0.70, 1.22, 1.90), (0.0014, 0.0025, 0.0142)),
    "Skin1": ((0.74, 0.88, 1.01), (0.032, 0.17, 0.48)),
    "Skin2": ((1.09, 1.59, 1.79), (0.013, 0.070, 0.145)),
    "Spectralon": ((11.6, 20.4, 14.9), (0.00, 0.00, 0.00)),
    "Wholemilk": ((2.55, 3.21, 3.77), (0.0011, 0.0024, 0.014)),
    "Lowfat Milk": ((0.89187, 1.5136, 2.532), (0.002875, 0.00575, 0.0115)),
    "Reduced Milk": ((2.4858, 3.1669, 4.5214), (0.0025556, 0.0051111, 0.012778)),
    "Regular Milk": ((4.5513, 5.8294, 7.136), (0.0015333, 0.0046, 0.019933)),
    "Espresso": ((0.72378, 0.84557, 1.0247), (4.7984, 6.5751, 8.8493)),
    "Mint Mocha Coffee": ((0.31602, 0.38538, 0.48131), (3.772, 5.8228, 7.82)),
    "Lowfat Soy Milk": ((0.30576, 0.34233, 0.61664), (0.0014375, 0.0071875, 0.035937)),
    "Regular Soy Milk": ((0.59223, 0.73866, 1.4693), (0.0019167, 0.0095833, 0.065167)),
    "Lowfat Chocolate Milk": ((0.64925, 0.83916, 1.1057), (0.0115, 0.0368, 0.1564)),
    "Regular Chocolate Milk": ((1.4585, 2.1289, 2.9527), (0.010063, 0.043125, 0.14375)),
    "Coke": ((8.9053e-05, 8.372e-05, 0.0), (0.10014, 0.16503, 0.2468)),
    "Pepsi": ((6.1697e-05, 4.2564e-05, 0.0), (0.091641, 0.14158, 0.20729)),
    "Sprite": ((6.0306e-06, 6.4139e-06, 6.5504e-06), (0.001886, 0.0018308, 0.0020025)),
    "Gatorade": ((0.0024574, 0.003007, 0.0037325), (0.024794, 0.019289, 0.008878)),
    "Chardonnay": ((1.7982e-05, 1.3758e-05, 1.2023e-05), (0.010782, 0.011855, 0.023997)),
    "White Zinfandel": ((1.7501e-05, 1.9069e-05, 1.288e-05), (0.012072, 0.016184, 0.019843)),
    "Merlot": ((2.1129e-05, 0.0, 0.0), (0.11632, 0.25191, 0.29434)),
    "Budweiser Beer": ((2.4356e-05, 2.4079e-05, 1.0564e-05), (0.011492, 0.024911, 0.057786)),
    "Coors Light Beer": ((5.0922e-05, 4.301e-05, 0.0), (0.006164, 0.013984, 0.034983)),
    "Clorox": ((0.0024035, 0.0031373, 0.003991), (0.0033542, 0.014892, 0.026297)),
    "Apple Juice": ((0.00013612, 0.00015836, 0.000227), (0.012957, 0.023741, 0.052184)),
    "Cranberry Juice": ((0.00010402, 0.00011646, 7.8139e-05), (0.039437, 0.094223, 0.12426)),
    "Grape Juice": ((5.382e-05, 0.0, 0.0), (0.10404, 0.23958, 0.29325)),
    "Ruby Grapefruit Juice": ((0.011002, 0.010927, 0.011036), (0.085867, 0.18314, 0.25262)),
    "White Grapefruit Juice": ((0.22826, 0.23998, 0.32748), (0.0138, 0.018831, 0.056781)),
    "Shampoo": ((0.0007176, 0.0008303, 0.0009016), (0.014107, 0.045693, 0.061717)),
    "Strawberry Shampoo": ((0.00015671, 0.00015947, 1.518e-05), (0.01449, 0.05796, 0.075823)),
    "Head & Shoulders Shampoo": ((0.023805, 0.028804, 0.034306), (0.084621, 0.15688, 0.20365)),
    "Lemon Tea Powder": ((0.040224, 0.045264, 0.051081), (2.4288, 4.5757, 7.2127)),
    "Orange Powder": ((0.00015617, 0.00017482, 0.0001762), (0.001449, 0.003441, 0.007863)),
    "Pink Lemonade Powder": ((0.00012103, 0.00013073, 0.00012528), (0.001165, 0.002366, 0.003195)),
    "Cappuccino Powder": ((1.8436, 2.5851, 2.1662), (35.844, 49.547, 61.084)),
    "Salt Powder": ((0.027333, 0.032451, 0.031979), (0.28415, 0.3257, 0.34148)),
    "Sugar Powder": ((0.00022272, 0.00025513, 0.000271), (0.012638, 0.031051, 0.050124)),
    "Suisse Mocha Powder": ((2.7979, 3.5452, 4.3365), (17.502, 27.004, 35.433)),
    "Pacific Ocean Surface Water": ((0.0001764, 0.00032095, 0.00019617), (0.031845, 0.031324, 0.030147)),
}


def resolve(values: dict[str, Any], loc: Location | None) -> tuple[dict[str, Any], int]:
    """The coefficients of the mode the given parameters choose (pbrt-v4's four ways), checked."""
    owner = f'material "{NAME}"'
    film = FILM if has_film(values) else 0
    v = resolve_roughness(resolve_film(values, owner, loc))
    given = {k for k in ("sigma_a", "sigma_s", "reflectance", "mfp") if k in values}

    def refuse_unused(names: set[str], why: str) -> None:
        if names:
            raise SceneError(f'{owner}: parameter(s) {", ".join(sorted(names))} unused {why} '
                             "(pbrt-v4 refuses unused parameters)", loc)

    if "name" in values:
        medium = NAMED_MEDIA.get(values["name"])
        if medium is None:
            raise UnsupportedError(f'{owner}: named medium "{values["name"]}" not found (known: '
                                   f'{", ".join(NAMED_MEDIA)})', loc)
        refuse_unused(given, 'with "name"')
        v["sigma_s"], v["sigma_a"] = medium     # g is taken as 0 by table_rows
        return v, _spectral_flag(v, film)
    if ("sigma_a" in values) != ("sigma_s" in values):
        have, missing = ("sigma_a", "sigma_s") if "sigma_a" in values else ("sigma_s", "sigma_a")
        raise SceneError(f'{owner}: "{have}" given without "{missing}"', loc)
    if "sigma_a" in values:
        refuse_unused(given & {"reflectance", "mfp"}, 'with "sigma_a" and "sigma_s"')
        return v, _spectral_flag(v, film)
    if "reflectance" in values:
        return v, _spectral_flag(v, FROM_REFLECTANCE | film)
    refuse_unused(given & {"mfp"}, 'without "reflectance"')
    return v, _spectral_flag(v, film)  # the declared defaults: whole milk


def _spectral_inputs(values: dict[str, Any], flags: int) -> tuple[str, str]:
    """The two colour parameters the body is made of in this mode."""
    return ("reflectance", "mfp") if flags & FROM_REFLECTANCE else ("sigma_a", "sigma_s")


def _spectra(values: dict[str, Any], flags: int) -> np.ndarray | None:
    """(2, 4) rows (c0, c1, c2, scale) of the body's two colours as pbrt-v4 upsamples them
    (reflectance as an albedo spectrum, the rest unbounded), or None where they are textures,
    grey (a constant spectrum: RGB is exact) or not representable."""
    names = _spectral_inputs(values, flags)
    rgb = [PARAMS.value(values, n) for n in names]
    if any(isinstance(v, TextureRef) for v in rgb):
        return None
    rgb = [np.broadcast_to(np.asarray(v, np.float64), (3,)) for v in rgb]
    if all(np.ptp(v) <= 1e-6 * max(float(np.max(v)), 1e-30) for v in rgb):
        return None
    rows = []
    for name, v in zip(names, rgb):
        c, scale, miss = rgb_spectrum.albedo(v) if name == "reflectance" else rgb_spectrum.unbounded(v)
        if miss > rgb_spectrum.TOLERANCE * max(scale, 1e-30):
            return None
        rows.append([c[0], c[1], c[2], scale])
    return np.asarray(rows, np.float32)


def _spectral_flag(values: dict[str, Any], flags: int) -> int:
    return flags | (SPECTRAL if _spectra(values, flags) is not None else 0)


def layer_rows(values: dict[str, Any], loc: Location | None) -> np.ndarray:
    """The boundary's stack in the scene's layer table (none without one)."""
    return stack_rows(values, loc, f'material "{NAME}"')


def has_coating(values: dict[str, Any]) -> bool:
    """Whether this material's boundary carries a film or stack (a kernel then compiles its lobes)."""
    return has_film(values)


def table_rows(values: dict[str, Any], loc: Location | None, thin_film: str) -> tuple[np.ndarray, str]:
    """The profile table for this material's (g, eta) (``values`` as ``resolve`` left them); a
    warning where pbrt-v4 warns: a non-zero g with a named medium is ignored (taken as 0)."""
    g = PARAMS.value(values, "g")
    warning = ""
    if "name" in values:
        if g != 0.0:
            warning = f'material "{NAME}": non-zero "g" ignored with the named medium "{values["name"]}"'
        g = 0.0
    rows = profile_rows(g, PARAMS.value(values, "eta"))
    flags = FROM_REFLECTANCE if "reflectance" in values else 0
    spectra = _spectra(values, flags)
    if spectra is not None:                 # after the profile: read by spectrum_row()
        rows = np.concatenate([rows, spectra])
    return rows, warning


@wp.func
def surface_alpha(b: BSDF) -> wp.vec2:
    return roughness_to_alpha(wp.vec2(b.p[SLOT.uroughness][0], b.p[SLOT.vroughness][0]),
                              (b.flags & FLAG.remaproughness) != 0)


@wp.func
def exit_normalisation(eta: float) -> float:
    """c = 1 − 2 FM1(1/eta) of Sw, with d'Eon and Irving's fit for eta < 1 (pbrt-v4's)."""
    e = 1.0 / eta
    e2 = e * e
    fm1 = float(0.0)
    if e < 1.0:
        fm1 = 0.45966 - 1.73965 * e + 3.37668 * e2 - 3.904945 * e2 * e + 2.49277 * e2 * e2 - 0.68441 * e2 * e2 * e
    else:
        fm1 = -4.61686 + 11.1136 * e - 10.4646 * e2 + 5.11455 * e2 * e - 1.27198 * e2 * e2 + 0.12746 * e2 * e2 * e
    return 1.0 - 2.0 * fm1


@wp.func
def _exit_value(eta: float, wi: wp.vec3) -> float:
    """Sw(wi) in radiance transport: eta² (1 − F(cos θi)) / (c π) above the surface; the eta² undoes
    the 1/eta² the entry's refraction applied."""
    if wi[2] <= 0.0:
        return 0.0
    return eta * eta * (1.0 - fresnel_dielectric(wi[2], eta)) * INV_PI / exit_normalisation(eta)


@wp.func
def bare_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    eta = b.p[SLOT.eta][0]
    if (b.flags & EXIT) != 0:
        ev = BSDFEval()
        if wo[2] > 0.0 and wi[2] > 0.0:
            ev.f = wp.vec3(_exit_value(eta, wi))
            ev.pdf = wi[2] * INV_PI
        return ev
    if (b.flags & SURFACE) != 0:
        if wo[2] * wi[2] <= 0.0:
            return BSDFEval()
        return dielectric_eval(eta, surface_alpha(b), wo, wi, REFLECTION, True)
    return dielectric_eval(eta, surface_alpha(b), wo, wi, REFLECTION | TRANSMISSION, True)


@wp.func
def bare_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    eta = b.p[SLOT.eta][0]
    if (b.flags & EXIT) != 0:
        s = exit_direction(wo, u)
        if s.pdf > 0.0:
            s.weight = wp.vec3(_exit_value(eta, s.wi) * s.wi[2] / s.pdf)
        return s
    sides = wp.where((b.flags & SURFACE) != 0, REFLECTION, REFLECTION | TRANSMISSION)
    return dielectric_sample(eta, surface_alpha(b), wo, u, sides, True)


@wp.func
def coating(b: BSDF) -> Coating:
    """The boundary's film or stack (:func:`renderer.materials.film_body.body_coating`)."""
    d = b.p[SLOT.thickness][0] + b.p[SLOT.thicknessscale][0] * b.p[SLOT.thicknessmap][0]
    return body_coating(b, b.p[SLOT.eta_film][0], b.p[SLOT.eta][0], d, b.p[SLOT.thickness][0])


@wp.func
def coated_eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    """The coated boundary's lobes: the exit lobe with the coating's T, its reflection alone, or both sides."""
    eta = b.p[SLOT.eta][0]
    if (b.flags & EXIT) != 0:
        return film_exit_eval(coating(b), eta, exit_normalisation(eta), wo, wi)
    return film_boundary_eval(coating(b), eta, surface_alpha(b), wo, wi, (b.flags & SURFACE) != 0)


@wp.func
def coated_sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    eta = b.p[SLOT.eta][0]
    if (b.flags & EXIT) != 0:
        return film_exit_sample(coating(b), eta, exit_normalisation(eta), wo, u)
    return film_boundary_sample(coating(b), eta, surface_alpha(b), wo, u, (b.flags & SURFACE) != 0)


@lru_cache(maxsize=None)
def _lobes(coated: bool) -> tuple[wp.Function, wp.Function]:
    """``eval_pdf`` and ``sample``, with the coated boundary's lobes compiled only where a kernel
    of ``coated`` scenes can reach them."""

    @wp.func
    def eval_pdf(b: BSDF, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
        if wp.static(coated):
            if (b.flags & FILM) != 0:
                return coated_eval_pdf(b, wo, wi)
        return bare_eval_pdf(b, wo, wi)

    @wp.func
    def sample(b: BSDF, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
        if wp.static(coated):
            if (b.flags & FILM) != 0:
                return coated_sample(b, wo, u)
        return bare_sample(b, wo, u)

    return eval_pdf, sample


#: Every lobe: what the tests and other code call directly.
eval_pdf, sample = _lobes(True)


def specialised(features: Any) -> tuple[wp.Function, wp.Function]:
    """``eval_pdf`` and ``sample`` with the coated boundary only where some subsurface material has one."""
    return _lobes(features.coated_body)


def exit_normalisation_host(eta: float) -> float:
    """The host value of ``exit_normalisation`` (for tests and docs)."""
    return 1.0 - 2.0 * fresnel_moment1(1.0 / eta)
