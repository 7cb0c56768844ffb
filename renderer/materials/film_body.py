"""A thin film or multilayer stack on the boundary of a translucent body (the ``subsurface``
material's optional coating): the coating's per-wavelength R and T, integrated to RGB by
:mod:`renderer.materials.coating`, replace the bare dielectric's F and 1 − F wherever a
diffusion BSSRDF crosses its boundary:

* where light arrives: the reflection lobe carries R, the light that enters carries T (the
  integrator's subsurface step chooses between them in proportion to their mean RGB);
* where light leaves: the exit lobe Sw(wi) = eta² T(cos θi) k / (c π), c the bare lobe's
  normalisation. Without k the lobe would let out T̄_coat / T̄_bare of what the bare one lets out
  (T̄ = 2∫T μ dμ); but what a film keeps inside is not lost, the body sends it back to the
  boundary. Counting those returns with the body's return albedo a (the chance that light sent
  back into it reaches the boundary again), a body of effective albedo rho_eff lets out
  E = a T̄_in / (1 − a R̄_in) of what enters, T̄_in = T̄/eta² (reciprocity), R̄_in = 1 − T̄_in
  (a lossless film), and a follows from the bare boundary's E = rho_eff. So
  k = E_coat T̄_bare / (E_bare T̄_coat) = (1 − a R̄_in,bare) / (1 − a R̄_in,coat): a white body
  (a = 1) lets out everything the film traps, k = T̄_bare / T̄_coat; a black one (a = 0) nothing,
  k = 1. k does not depend on wi, so the step charges it with the entry weight (``exit_balance``)
  and the lobe's value and density stay a product of T and the cosine.

Where a film is 0 nm thick its R and T are the bare Fresnel's to float rounding, so these lobes
are the bare material's. What the film does to the diffusion's own boundary condition (its
internal reflection changes the profile) is not modelled: the profile stays the bare boundary's
(docs/thinfilm.md, "A film over a translucent body", measures what that costs).

The body's parameters and slots are the ``subsurface`` material's; the coating's are declared
here once (``FILM_PARAMS``) with the names ``thinfilm`` uses for its film and stack.
"""
from __future__ import annotations

from typing import Any

import warp as wp

from renderer.errors import Location
from renderer.materials import thinfilm
from renderer.materials.bsdf import (BSDF, DIFFUSE, REFLECTION, TRANSMISSION, BSDFEval, BSDFSample, failed_sample)
from renderer.materials.coating import BOTH_SIDES, Coating, coating_eval, coating_rgb, coating_sample
from renderer.materials.stack import STACK_PARAMS, has_stack, resolve_stack
from renderer.optics.fresnel import fresnel_dielectric
from renderer.parameters import Parameter
from renderer.sampling.warps import cosine_hemisphere
from renderer.vecmath import INV_PI

FILM_PARAMS = (
    thinfilm.PARAMS.by_name["eta_film"],
    Parameter("thickness", "float", None, 0.0, texture=True,
              doc="a film on the boundary (nm; 0: the bare boundary to float rounding); a stack's is its total"),
    thinfilm.PARAMS.by_name["thicknessmap"],
    thinfilm.PARAMS.by_name["thicknessscale"],
    *STACK_PARAMS,
)
#: Nodes of the midpoint rule in μ² for the hemispherical means of the exit's balance.
BALANCE_NODES = wp.constant(16)


def has_film(values: dict[str, Any]) -> bool:
    """A film is given by its thickness (or a map of it) or by a stack's layers."""
    return "thickness" in values or "thicknessmap" in values or has_stack(values)


def resolve_film(values: dict[str, Any], owner: str, loc: Location | None) -> dict[str, Any]:
    """The stack checked and its total thickness derived, as ``thinfilm`` does; a single film's
    thickness defaults to 0 where only a map is given."""
    values = resolve_stack(values, loc, owner)      # refuses a stack's parameters without its layers
    if not has_film(values) or "thickness" in values:
        return values
    return values | {"thickness": 0.0}


@wp.func
def body_coating(b: BSDF, n_film: float, eta: float, d: float, total: float) -> Coating:
    """Vacuum | a film of index n_film and thickness d nm (or the material's stack, of unmapped
    total ``total``, scaled to d) | the body of index eta: a clear substrate, balanced so that a
    flat spectrum is exact at every wavelength jitter."""
    c = Coating()
    c.n_outer = 1.0
    c.n_film = n_film
    c.n_inner = wp.vec2(eta, 0.0)
    c.d = wp.max(d, 0.0)
    c.total = total
    c.clear = True
    c.balanced = True
    c.layers = b.layers
    c.layer_first = b.layer_first
    c.layer_count = b.layer_count
    c.spectral_n = b.spectral_n
    c.wavelength_u = b.wavelength_u
    c.spectral = b.spectral
    c.table_first = 0          # the material's own table is the BSSRDF's profile, not the coating's
    return c


@wp.func
def exit_balance(c: Coating, eta: float, rho_eff: wp.vec3) -> wp.vec3:
    """k per channel (see the module docstring): (1 − a R̄_bare) / (1 − a R̄_coat), R̄ = 1 − T̄/eta² the
    hemispherical internal reflectance (T̄ = 2∫T μ dμ from outside, midpoint rule in μ²; reciprocity
    makes T̄/eta² the inside's), a = rho_eff / (T̄_bare/eta² + rho_eff R̄_bare) the body's return albedo."""
    bare = float(0.0)
    coat = wp.vec3(0.0)
    for j in range(BALANCE_NODES):
        mu = wp.sqrt((float(j) + 0.5) / float(BALANCE_NODES))
        r, t = coating_rgb(c, mu)
        coat += t
        bare += 1.0 - fresnel_dielectric(mu, eta)
    inv = 1.0 / (float(BALANCE_NODES) * eta * eta)
    t_bare = bare * inv
    k = wp.vec3(0.0)
    for ch in range(3):
        rho = wp.clamp(rho_eff[ch], 0.0, 1.0)
        a = rho / wp.max(t_bare + rho * (1.0 - t_bare), 1.0e-12)
        k[ch] = (1.0 - a * (1.0 - t_bare)) / wp.max(1.0 - a * (1.0 - coat[ch] * inv), 1.0e-12)
    return k


@wp.func
def film_exit_value(c: Coating, eta: float, norm: float, wi: wp.vec3) -> wp.vec3:
    """eta² T(cos θi) / (c π) above the surface (k is charged by the step)."""
    if wi[2] <= 0.0:
        return wp.vec3(0.0)
    r, t = coating_rgb(c, wi[2])
    return t * (eta * eta * INV_PI / norm)


@wp.func
def film_exit_eval(c: Coating, eta: float, norm: float, wo: wp.vec3, wi: wp.vec3) -> BSDFEval:
    ev = BSDFEval()
    if wo[2] > 0.0 and wi[2] > 0.0:
        ev.f = film_exit_value(c, eta, norm, wi)
        ev.pdf = wi[2] * INV_PI
    return ev


@wp.func
def exit_direction(wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    """The exit lobe's cosine-distributed direction above the surface (bare or coated), with its
    density; the caller weights it by its own lobe (a failed sample has pdf 0)."""
    if wo[2] <= 0.0:
        return failed_sample()
    wi = cosine_hemisphere(wp.vec2(u[0], u[1]))
    if wi[2] <= 0.0:
        return failed_sample()
    s = BSDFSample()
    s.wi = wi
    s.pdf = wi[2] * INV_PI
    s.flags = REFLECTION | DIFFUSE
    return s


@wp.func
def film_exit_sample(c: Coating, eta: float, norm: float, wo: wp.vec3, u: wp.vec3) -> BSDFSample:
    """A cosine-distributed exit direction, weighted by the lobe over its density."""
    s = exit_direction(wo, u)
    if s.pdf > 0.0:
        s.weight = film_exit_value(c, eta, norm, s.wi) * (s.wi[2] / s.pdf)
    return s


@wp.func
def film_boundary_eval(c: Coating, eta: float, alpha: wp.vec2, wo: wp.vec3, wi: wp.vec3, surface: bool) -> BSDFEval:
    """The coated boundary: its reflection alone on the step's surface route (``surface``), else both sides."""
    if surface:
        if wo[2] * wi[2] <= 0.0:
            return BSDFEval()
        return coating_eval(c, eta, alpha, wo, wi, REFLECTION, True)
    return coating_eval(c, eta, alpha, wo, wi, BOTH_SIDES, True)


@wp.func
def film_boundary_sample(c: Coating, eta: float, alpha: wp.vec2, wo: wp.vec3, u: wp.vec3, surface: bool) -> BSDFSample:
    sides = wp.where(surface, REFLECTION, REFLECTION | TRANSMISSION)
    return coating_sample(c, eta, alpha, wo, u, sides, True)


@wp.func
def entry_share(c: Coating, cos_o: float) -> float:
    """q: the probability that a path arriving from outside enters, the coating's mean T over its
    mean R + T at the macroscopic normal (the bare boundary's 1 − F where the film is 0 nm)."""
    r, t = coating_rgb(c, cos_o)
    total = (r[0] + r[1] + r[2]) + (t[0] + t[1] + t[2])
    return wp.where(total > 0.0, (t[0] + t[1] + t[2]) / wp.max(total, 1.0e-30), 0.0)


@wp.func
def entry_weight(c: Coating, eta: float, alpha: wp.vec2, wo_local: wp.vec3, u: wp.vec3) -> wp.vec3:
    """Given entry, the refracted sample's weight (T, 1/eta'² and the microfacet terms over the
    density); 0 where the sample fails."""
    s = coating_sample(c, eta, alpha, wo_local, u, TRANSMISSION, True)
    if s.pdf <= 0.0:
        return wp.vec3(0.0)
    return s.weight
