"""The directional albedo of a compensated clear coating by deterministic quadrature, split into the
errors of its parts, so a bias of 1e-4 per bounce (which a closed object compounds over tens of
internal bounces) can be seen without 10⁸ Monte Carlo samples.

Single scattering is integrated by the midpoint rule over an S×S grid of visible normals (Heitz 2018): the
expected weight R(c) G2(wo, wr)/G1(wo) + T(c) G2(wo, wt)/G1(wo) with the coating's own RGB R and T at
the facet cosine c, which is what Walter et al.'s lobes (``coating_eval``) integrate to. The lobe that
puts the rest back returns exactly L(μo) (its shares integrate to 1), so a lossless coating's albedo
is E_ss(μ) + L(μ), and 1 − that is the bias per bounce. The same grid gives the bare dielectric's
E_d(μ) and the facet weights K_j(μ) at the exact (μ, α, e), to set against the tables' interpolated
values: the bias is (E_d − Ê_d) + Σ ρ_j (K_j − K̂_j) + (E_ss − E_d − Σ ρ_j K_j), the tables' error in E_d,
their error in K, and the error of interpolating ρ linearly between the nodes."""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import warp as wp

from bsdf_harness import _bsdf_inputs, bsdf_from_rows
from renderer.materials import thinfilm
from renderer.materials.bsdf import Slots
from renderer.materials.coating import coating_rgb
from renderer.materials.coating_energy import coat_energy
from renderer.materials.energy import (FACET_NODES, FacetVector, dielectric_albedo, facet_weights,
                                       node_coordinate)
from renderer.materials.energy_build import facet_masking
from renderer.materials.microfacet import ggx_G1, ggx_sample_visible
from renderer.optics.fresnel import fresnel_dielectric


@wp.struct
class AlbedoParts:
    ss: wp.vec3              # the coating's single-scattering albedo
    bare: float              # the bare dielectric's
    bare_table: float        # Ê_d, the table's
    loss: wp.vec3            # L(μ), what the lobe returns
    k: FacetVector           # K_j at (μ, α, e), by the same quadrature
    k_table: FacetVector     # K̂_j, interpolated from the table
    rho_r: FacetVector       # ρ at the nodes, as the lobe read it
    rho_g: FacetVector
    rho_b: FacetVector


@lru_cache(maxsize=1)
def _kernel():
    @wp.kernel(module="unique")
    def parts(p: Slots, flags: int, kind: int, layers: wp.array(dtype=wp.vec4), first: int, count: int,
              mus: wp.array(dtype=float), alpha: float, strata: int, out: wp.array(dtype=AlbedoParts)):
        """mus < 0: wo inside the substrate."""
        i = wp.tid()
        b = bsdf_from_rows(p, flags, kind, layers, first, count)
        c = thinfilm.film_coating(b)
        eta = b.p[thinfilm.SLOT.eta_inner][0] / b.p[thinfilm.SLOT.eta_outer][0]
        side = wp.where(mus[i] > 0.0, 1.0, -1.0)
        mu = wp.abs(mus[i])
        e = wp.where(side > 0.0, eta, 1.0 / eta)
        wo = wp.vec3(wp.sqrt(1.0 - mu * mu), 0.0, mu)       # local: wo up, relative index e
        a2 = wp.vec2(alpha, alpha)
        g1 = ggx_G1(wo, a2)
        ss = wp.vec3(0.0)
        bare = float(0.0)
        k = FacetVector()
        for n in range(strata * strata):
            # the midpoint rule on the grid of the visible normals' unit square
            wm = ggx_sample_visible(wo, a2, (wp.vec2(float(n % strata), float(n / strata)) + wp.vec2(0.5)) / float(strata))
            cm = wp.dot(wo, wm)
            r, t = coating_rgb(c, cm * side)
            f = fresnel_dielectric(cm, e)
            gs = facet_masking(wo, wm, a2, e, g1)
            gr = gs[0]
            gt = gs[1]
            ss += r * gr + t * gt
            bare += f * gr + (1.0 - f) * gt
            x = wp.clamp(node_coordinate(cm, e), 0.0, 1.0) * float(FACET_NODES - 1)
            j = wp.min(int(x), FACET_NODES - 2)
            h = (1.0 - f) * (gr - gt)
            k[j] = k[j] + h * (1.0 - (x - float(j)))
            k[j + 1] = k[j + 1] + h * (x - float(j))
        nn = float(strata * strata)
        o = AlbedoParts()
        o.ss = ss / nn
        o.bare = bare / nn
        o.k = k / nn
        o.bare_table = dielectric_albedo(layers, mu, alpha, e)
        o.k_table = facet_weights(layers, mu, alpha, e)
        q = coat_energy(c, eta, a2, wp.vec3(wo[0], 0.0, mu * side), layers)
        o.loss = q.l_o
        o.rho_r = q.shift_a.r
        o.rho_g = q.shift_a.g
        o.rho_b = q.shift_a.b
        out[i] = o

    return parts


def albedo_parts(values: dict, mus, alpha: float, strata: int = 256) -> dict[str, np.ndarray]:
    """For a clear ``thinfilm`` (its parameters ``values``) at isotropic GGX ``alpha``, per cosine in
    ``mus`` (negative: from inside): ``albedo`` E_ss + L (n, 3) and the bias 1 − albedo split into
    ``table_bare`` (n,), ``table_k`` (n, 3) and ``rho_interpolation`` (n, 3)."""
    mus = np.asarray(mus, dtype=np.float64)
    out = wp.zeros(len(mus), dtype=AlbedoParts, device="cpu")
    wp.launch(_kernel(), dim=len(mus), inputs=[*_bsdf_inputs("thinfilm", values),
                                                wp.array(mus.astype(np.float32), dtype=float, device="cpu"),
                                                float(alpha), strata, out], device="cpu")
    o = out.numpy()
    ss = np.asarray(o["ss"], np.float64)
    k = np.asarray(o["k"], np.float64)
    k_t = np.asarray(o["k_table"], np.float64)
    rho = np.stack([np.asarray(o[f"rho_{ch}"], np.float64) for ch in "rgb"], axis=1)     # (n, 3, nodes)
    bare = np.asarray(o["bare"], np.float64)
    bare_t = np.asarray(o["bare_table"], np.float64)
    albedo = ss + np.asarray(o["loss"], np.float64)
    return {"albedo": albedo, "ss": ss, "table_bare": bare_t - bare,
            "table_k": np.einsum("ncj,nj->nc", rho, k_t - k),
            "rho_interpolation": bare[:, None] + np.einsum("ncj,nj->nc", rho, k) - ss}
