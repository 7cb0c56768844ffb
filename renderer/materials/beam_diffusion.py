"""The photon beam diffusion (PBD) profile of pbrt-v4's ``subsurface`` material, tabulated on the host.

A semi-infinite homogeneous medium of single-scattering albedo rho (sigma_t = 1: radii are optical
radii) lit by a narrow beam returns, at distance r from the beam, the radiant exitance
S(r) = S_ss(r) + S_ms(r) (pbrt-v4's book, "Light transport III: BSSRDFs", after Habel et al. 2013):

- S_ms integrates the classical dipole (with Grosjean's non-classical diffusion coefficient
  D_G = (2 sigma_a + sigma_s') / (3 sigma_t'^2) and d'Eon and Irving's extrapolated boundary
  z_e = -2 D_G (1 + 3 FM2) / (1 - 2 FM1)) over point sources spread exponentially along the
  refracted beam, each exiting with c_phi phi + c_E E and damped by kappa = 1 - e^{-2 sigma_t'(d_r + z_r)};
- S_ss is single scattering along the beam below the critical angle, leaving with Henyey–Greenstein
  phase and the boundary's Fresnel transmittance.

The table holds 2 pi r S(r) at 100 albedos (rho_i = (1 - e^{-8 i / 99}) / (1 - e^{-8})) and 64
radii (0, then 2.5e-3 growing by 1.2 per node, to 203 mean free paths), its running integral under
the Catmull-Rom spline through the nodes (the radius CDF), and the integral, the effective albedo
rho_eff(rho), as pbrt-v4 builds it (100 and 64 nodes, 100 samples per integral, the same node
placements and the same Fresnel-moment fits). It depends only on (g, eta) and takes ~0.1 s, so it
is built when a scene is uploaded and kept for the process (``lru_cache``).

``albedo_from_reflectance`` inverts rho_eff(rho) (pbrt-v4's SubsurfaceFromDiffuse), so a
``reflectance`` and ``mfp`` give sigma_s = rho / mfp, sigma_a = (1 - rho) / mfp.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

N_RHO = 100
N_RADIUS = 64
#: Samples of the integrals over the beam (per albedo and radius), as pbrt-v4.
N_BEAM = 100
#: Nodes of the inverse table rho(rho_eff), uniform in rho_eff.
N_INVERSE = 1024
#: The share of the profile inside the probe sphere (pbrt-v4's r_max: its 99.9 % radius).
PROBE_QUANTILE = 0.999


def albedo_nodes() -> np.ndarray:
    i = np.arange(N_RHO, dtype=np.float64)
    return (1.0 - np.exp(-8.0 * i / (N_RHO - 1))) / (1.0 - np.exp(-8.0))


def radius_nodes() -> np.ndarray:
    r = np.zeros(N_RADIUS)
    r[1:] = 2.5e-3 * 1.2 ** np.arange(N_RADIUS - 1)
    return r


def fresnel_dielectric(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance, eta = n_t / n_i; cos_i < 0 arrives from the eta side."""
    c = np.clip(np.asarray(cos_i, np.float64), -1.0, 1.0)
    e = np.where(c < 0.0, 1.0 / eta, eta)
    c = np.abs(c)
    sin2_t = (1.0 - c * c) / (e * e)
    cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):    # 0/0 only under total internal reflection
        r_s = (c - e * cos_t) / (c + e * cos_t)
        r_p = (e * c - cos_t) / (e * c + cos_t)
    return np.where(sin2_t >= 1.0, 1.0, 0.5 * (r_s * r_s + r_p * r_p))


def fresnel_moment1(eta: float) -> float:
    """The first Fresnel moment 2∫F(mu) mu dmu / 2 as the polynomial fits of d'Eon and Irving (2011)
    that pbrt-v4 uses (so our table is pbrt's; a direct quadrature differs by < 0.3 %)."""
    e = [eta ** k for k in range(6)]
    if eta < 1.0:
        c = (0.45966, -1.73965, 3.37668, -3.904945, 2.49277, -0.68441)
    else:
        c = (-4.61686, 11.1136, -10.4646, 5.11455, -1.27198, 0.12746)
    return float(sum(ci * ei for ci, ei in zip(c, e)))


def fresnel_moment2(eta: float) -> float:
    """The second Fresnel moment, d'Eon and Irving's fit (pbrt-v4's)."""
    e = [eta ** k for k in range(6)]
    if eta < 1.0:
        c = (0.27614, -0.87350, 1.12077, -0.65095, 0.07883, 0.04860)
        return float(sum(ci * ei for ci, ei in zip(c, e)))
    r = 1.0 / eta
    return float(-547.033 + 45.3087 * r ** 3 - 218.725 * r ** 2 + 458.843 * r + 404.557 * eta
                 - 189.519 * eta ** 2 + 54.9327 * eta ** 3 - 9.00603 * eta ** 4 + 0.63942 * eta ** 5)


def _beam_depths(sigma_t: np.ndarray) -> np.ndarray:
    """N_BEAM depths per coefficient, stratified in the exponential's CDF (midpoints): (..., N_BEAM)."""
    u = (np.arange(N_BEAM) + 0.5) / N_BEAM
    return -np.log1p(-u) / np.asarray(sigma_t)[..., None]


def multiple_scattering(sigma_s: np.ndarray, sigma_a: np.ndarray, g: float, eta: float, r: np.ndarray) -> np.ndarray:
    """S_ms(r): the PBD dipole sum over the beam (shapes of sigma_s, sigma_a and r broadcast)."""
    sigma_s, sigma_a, r = np.broadcast_arrays(np.asarray(sigma_s, float), np.asarray(sigma_a, float),
                                              np.asarray(r, float))
    sps = sigma_s * (1.0 - g)                    # reduced scattering
    spt = sigma_a + sps
    rhop = sps / spt
    D = (2.0 * sigma_a + sps) / (3.0 * spt * spt)
    sigma_tr = np.sqrt(np.maximum(sigma_a / D, 0.0))
    fm1, fm2 = fresnel_moment1(eta), fresnel_moment2(eta)
    ze = -2.0 * D * (1.0 + 3.0 * fm2) / (1.0 - 2.0 * fm1)
    c_phi, c_e = 0.25 * (1.0 - 2.0 * fm1), 0.5 * (1.0 - 3.0 * fm2)
    zr = _beam_depths(spt)
    zv = 2.0 * ze[..., None] - zr
    rr = r[..., None]
    dr = np.sqrt(rr * rr + zr * zr)
    dv = np.sqrt(rr * rr + zv * zv)
    st = sigma_tr[..., None]
    er, ev = np.exp(-st * dr), np.exp(-st * dv)
    phi = (er / dr - ev / dv) / (4.0 * np.pi * D[..., None])
    edn = (zr * (1.0 + st * dr) * er / dr ** 3 - zv * (1.0 + st * dv) * ev / dv ** 3) / (4.0 * np.pi)
    kappa = 1.0 - np.exp(-2.0 * spt[..., None] * (dr + zr))
    return (kappa * rhop[..., None] ** 2 * (c_phi * phi + c_e * edn)).mean(-1)


def _henyey_greenstein(cos_t: np.ndarray, g: float) -> np.ndarray:
    denom = 1.0 + g * g + 2.0 * g * cos_t
    return (1.0 - g * g) / (4.0 * np.pi * denom * np.sqrt(np.maximum(denom, 0.0)))


def single_scattering(sigma_s: np.ndarray, sigma_a: np.ndarray, g: float, eta: float, r: np.ndarray) -> np.ndarray:
    """S_ss(r): single scattering along the refracted beam, from the depth below which the exit
    direction lies within the critical angle."""
    sigma_s, sigma_a, r = np.broadcast_arrays(np.asarray(sigma_s, float), np.asarray(sigma_a, float),
                                              np.asarray(r, float))
    sigma_t = sigma_a + sigma_s
    rho = sigma_s / sigma_t
    t_crit = r * np.sqrt(max(eta * eta - 1.0, 0.0))
    t = t_crit[..., None] + _beam_depths(sigma_t)
    d = np.sqrt(r[..., None] ** 2 + t * t)
    cos_o = t / d
    term = (rho[..., None] * np.exp(-sigma_t[..., None] * (d + t_crit[..., None])) / (d * d)
            * _henyey_greenstein(cos_o, g) * (1.0 - fresnel_dielectric(-cos_o, eta)) * np.abs(cos_o))
    return term.mean(-1)


def _slopes(x: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per interval [x_k, x_k+1] the Hermite end slopes times the width, from finite differences of
    the neighbours (one-sided at the ends): the Catmull-Rom spline pbrt-v4 interpolates with."""
    w = np.diff(x)
    d0 = np.empty_like(f[..., :-1])
    d1 = np.empty_like(f[..., :-1])
    d0[..., 0] = f[..., 1] - f[..., 0]
    d0[..., 1:] = w[1:] * (f[..., 2:] - f[..., :-2]) / (x[2:] - x[:-2])
    d1[..., -1] = f[..., -1] - f[..., -2]
    d1[..., :-1] = w[:-1] * (f[..., 2:] - f[..., :-2]) / (x[2:] - x[:-2])
    return d0, d1


def spline_integral(x: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The running integral of the Catmull-Rom spline through (x, f) at every node (last axis)."""
    d0, d1 = _slopes(x, f)
    seg = ((d0 - d1) / 12.0 + 0.5 * (f[..., :-1] + f[..., 1:])) * np.diff(x)
    return np.concatenate([np.zeros_like(f[..., :1]), np.cumsum(seg, -1)], -1)


def spline_eval(x: np.ndarray, f: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The Catmull-Rom spline through (x, f) (1-D) at t (inside [x0, xn])."""
    k = np.clip(np.searchsorted(x, t, side="right") - 1, 0, len(x) - 2)
    d0, d1 = _slopes(x, f)
    s = (t - x[k]) / (x[k + 1] - x[k])
    s2, s3 = s * s, s * s * s
    return ((2 * s3 - 3 * s2 + 1) * f[k] + (s3 - 2 * s2 + s) * d0[k] + (-2 * s3 + 3 * s2) * f[k + 1]
            + (s3 - s2) * d1[k])


@dataclass(frozen=True)
class ProfileTable:
    rho: np.ndarray         # (N_RHO,) albedo nodes
    radius: np.ndarray      # (N_RADIUS,) optical radius nodes
    profile: np.ndarray     # (N_RHO, N_RADIUS) 2 pi r S(r)
    cdf: np.ndarray         # (N_RHO, N_RADIUS) its running spline integral
    rho_eff: np.ndarray     # (N_RHO,) the whole integral: the effective albedo
    inverse: np.ndarray     # (N_INVERSE,) rho at rho_eff = k / (N_INVERSE - 1) * rho_eff[-1]
    r_max: np.ndarray       # (N_RHO,) optical radius holding PROBE_QUANTILE of the profile (CDF nodes, linear)


@lru_cache(maxsize=8)
def profile_table(g: float, eta: float) -> ProfileTable:
    """The tabulated PBD profile for a Henyey–Greenstein g and relative index eta (cached)."""
    rho, radius = albedo_nodes(), radius_nodes()
    R, P = np.meshgrid(radius, rho)
    profile = 2.0 * np.pi * R * (single_scattering(P, 1.0 - P, g, eta, R) + multiple_scattering(P, 1.0 - P, g, eta, R))
    cdf = spline_integral(radius, profile)
    rho_eff = cdf[:, -1].copy()
    targets = np.linspace(0.0, rho_eff[-1], N_INVERSE)
    r_max = np.array([np.interp(PROBE_QUANTILE * c[-1], c, radius) if c[-1] > 0 else 0.0 for c in cdf])
    return ProfileTable(rho, radius, profile, cdf, rho_eff, _invert(rho, rho_eff, targets), r_max)


def _invert(x: np.ndarray, f: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """x with spline(x) = target for a monotone spline through (x, f), by bisection (clamped at the ends,
    as pbrt-v4's InvertCatmullRom)."""
    lo = np.full_like(targets, x[0])
    hi = np.full_like(targets, x[-1])
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = spline_eval(x, f, mid) < targets
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    out = 0.5 * (lo + hi)
    out = np.where(targets <= f[0], x[0], out)
    return np.where(targets >= f[-1], x[-1], out)


def albedo_from_reflectance(table: ProfileTable, reflectance: np.ndarray) -> np.ndarray:
    """The single-scattering albedo whose effective albedo is ``reflectance`` (host version of the
    device lookup: linear in the inverse table)."""
    r = np.clip(np.asarray(reflectance, np.float64), 0.0, 1.0)
    x = r / table.rho_eff[-1] * (N_INVERSE - 1)
    return np.interp(x, np.arange(N_INVERSE), table.inverse)


#: Where each part of the table sits in a material's flattened rows (floats, after one header row).
OFF_RHO = 0
OFF_RADIUS = OFF_RHO + N_RHO
OFF_EFF = OFF_RADIUS + N_RADIUS
OFF_PROFILE = OFF_EFF + N_RHO
OFF_CDF = OFF_PROFILE + N_RHO * N_RADIUS
OFF_INVERSE = OFF_CDF + N_RHO * N_RADIUS
OFF_RMAX = OFF_INVERSE + N_INVERSE
N_FLOATS = OFF_RMAX + N_RHO
#: Rows of the table in the layer table (the header, then the floats four to a row).
N_ROWS = 1 + (N_FLOATS + 3) // 4


def table_rows(g: float, eta: float) -> np.ndarray:
    """The table as (n, 4) float32 rows for the scene's layer table: a header row (the number of
    floats and rho_eff at rho = 1), then every float in the order of the OFF_* offsets."""
    t = profile_table(float(g), float(eta))
    flat = np.concatenate([t.rho, t.radius, t.rho_eff, t.profile.ravel(), t.cdf.ravel(), t.inverse, t.r_max])
    assert flat.size == N_FLOATS
    pad = (-flat.size) % 4
    body = np.concatenate([flat, np.zeros(pad)]).reshape(-1, 4)
    header = np.array([[N_FLOATS, t.rho_eff[-1], 0.0, 0.0]])
    rows = np.concatenate([header, body]).astype(np.float32)
    assert len(rows) == N_ROWS
    return rows
