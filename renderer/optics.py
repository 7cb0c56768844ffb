"""Wave optics on the device: Fresnel equations and thin-film interference (Warp functions).

Conventions, shared by every function here:

* Time dependence exp(-iωt); a complex index is n + ik with k ≥ 0 (absorbing). Complex numbers
  are ``wp.vec2`` (re, im).
* The normal component of a wave vector in medium j, in units of the vacuum wavenumber, is
  q_j = n_j cos θ_j = sqrt(n_j² − n_0² sin² θ_0) (Snell's law, complex). We write the radicand as
  (n_j − n_0)(n_j + n_0) + q_0², so equal indices give bit-identical q, and take the root with
  Im q ≥ 0: a wave that decays into the medium. Beyond a critical angle q_j is imaginary, so total
  internal reflection, frustrated TIR in a film thinner than λ, and metals (complex n_j) all come
  out of the same formulas with no special cases.
* q_0² carries a vanishing imaginary part (1e-12) so that q is never exactly 0 (grazing incidence,
  or a film at exactly its own critical angle), where the Airy terms would be 0/0 although their
  limits are finite. It shifts reflectances by less than 1e-6.
* Fresnel amplitudes are signed (Born & Wolf / Hecht). The π phase change on reflection at a
  denser medium is the sign of r; it must not be added again to the film phase (the classic
  tutorial error that turns an antireflection coat into a mirror: MgF2 on glass must go from
  R = 0.0426 bare to 0.0126 at a quarter wave).
* The incident medium n_0 is real (lossless): reflectance is only defined there.

Thick films. A sample at wavelength λ that stands for a band of width Δλ (a stratum of the
spectral integral) should return the band average of R, not R(λ): otherwise, once the fringe
spacing λ²/OPD drops below Δλ, a deterministic set of wavelengths aliases the fringes into false
colour. Across the band the round-trip phase φ = 2π·OPD/λ spreads by W = 2π·OPD·Δλ/λ². The box
average of the Airy function over that phase interval multiplies its k-th Fourier harmonic by
sinc(kW/2); we apply the first harmonic's factor (the only sizeable one unless both interfaces
reflect strongly) to the whole oscillating part: R = R_inc + γ·(R_coherent − R_inc), γ = sinc(W/2),
where the incoherent sum R_inc adds the intensities of the multiply reflected beams (the exact
phase average). γ is the box's own transfer function, not a smooth stand-in for it, because it
has to vanish when a band spans a whole fringe: then midpoint samples of band averages integrate
the fringes exactly, where a Gaussian of the same variance still lets 19 % through and aliases.
Physically this is light of coherence length ≈ λ²/Δλ: a 1 nm reference band means ≈ 300 µm, a
32-stratum sample ≈ 20 µm, so a 100 µm film converges to the incoherent result in every spectral
mode while films of a few µm keep their (pale, high-order) colours. Δλ = 0 is the exact
monochromatic Airy formula, and it is what the renderer's jittered estimator uses: a uniformly
jittered wavelength per stratum is already an unbiased estimate of the spectral integral, fringes
finer than a stratum only add noise that falls with spp, and band-averaging there would instead
blur the colour-matching functions by a stratum (a bias of several ΔE00 at N = 8).

``fast_math`` stays off: round-trip phases reach 10^4 radians for thick films. The phase is
reduced modulo one cycle before the cosine, so float32 keeps ~1e-3 rad of absolute phase accuracy.
"""
from __future__ import annotations

import numpy as np
import warp as wp

from renderer import spectral

wp.set_module_options({"fast_math": False, "enable_backward": False})

# Imaginary part added to q_0² (see the module docstring): keeps every q off exactly zero.
_Q2_EPS = wp.constant(1.0e-12)
# Denominators below this are roundoff at a degenerate point, never physics.
_TINY = wp.constant(1.0e-30)


# ---------------------------------------------------------------------------------------------
# Complex arithmetic on wp.vec2 (re, im)


@wp.func
def c_mul(a: wp.vec2, b: wp.vec2) -> wp.vec2:
    return wp.vec2(a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0])


@wp.func
def c_div(a: wp.vec2, b: wp.vec2) -> wp.vec2:
    """a / b, scaled by the larger component of b so that |b|² cannot overflow or underflow."""
    if wp.abs(b[0]) >= wp.abs(b[1]):
        t = b[1] / b[0]
        den = b[0] + b[1] * t
        return wp.vec2((a[0] + a[1] * t) / den, (a[1] - a[0] * t) / den)
    t = b[0] / b[1]
    den = b[0] * t + b[1]
    return wp.vec2((a[0] * t + a[1]) / den, (a[1] * t - a[0]) / den)


@wp.func
def c_sqrt(z: wp.vec2) -> wp.vec2:
    """Principal square root (Re ≥ 0; Im takes the sign of Im z, +0 counting as positive).

    The larger component comes from sqrt((|z| + |Re z|)/2) and the smaller from Im z divided by it,
    so neither suffers cancellation (a tiny absorption survives next to a large real part).
    """
    mag = wp.sqrt(z[0] * z[0] + z[1] * z[1])
    t = wp.sqrt(0.5 * (mag + wp.abs(z[0])))
    if t == 0.0:
        return wp.vec2(0.0, 0.0)
    if z[0] >= 0.0:
        return wp.vec2(t, 0.5 * z[1] / t)
    if z[1] < 0.0:
        return wp.vec2(0.5 * wp.abs(z[1]) / t, -t)
    return wp.vec2(0.5 * z[1] / t, t)


@wp.func
def c_expi(phase: float) -> wp.vec2:
    """exp(i·phase)."""
    return wp.vec2(wp.cos(phase), wp.sin(phase))


@wp.func
def c_abs2(z: wp.vec2) -> float:
    return z[0] * z[0] + z[1] * z[1]


@wp.func
def c_conj(z: wp.vec2) -> wp.vec2:
    return wp.vec2(z[0], -z[1])


# ---------------------------------------------------------------------------------------------
# Single interfaces


@wp.func
def normal_component_sq(cos0: float, n0: float) -> wp.vec2:
    """q_0² = (n_0 cos θ_0)², regularised (see module docstring)."""
    q0 = n0 * cos0
    return wp.vec2(q0 * q0, _Q2_EPS)


@wp.func
def normal_component(q0_sq: wp.vec2, n0: float, n: wp.vec2) -> wp.vec2:
    """q = n cos θ in a medium of complex index n, from Snell's law; Im q ≥ 0 (decaying)."""
    return c_sqrt(c_mul(wp.vec2(n[0] - n0, n[1]), wp.vec2(n[0] + n0, n[1])) + q0_sq)


@wp.func
def fresnel_amplitudes(qi: wp.vec2, qj: wp.vec2, wi: wp.vec2, wj: wp.vec2, nn: wp.vec2):
    """(r_ij, t_ij, t_ji) for light going from medium i to j.

    One formula for both polarisations: s uses wi = wj = nn = 1; p uses the permittivities
    wi = n_i², wj = n_j² and nn = n_i n_j (then r_p = (n_j² q_i − n_i² q_j)/(n_j² q_i + n_i² q_j),
    Hecht's sign, and t_p is the ratio of electric field amplitudes).
    """
    a = c_mul(wj, qi)
    b = c_mul(wi, qj)
    den = a + b
    two_nn = 2.0 * nn
    return c_div(a - b, den), c_div(c_mul(two_nn, qi), den), c_div(c_mul(two_nn, qj), den)


@wp.func
def fresnel_dielectric(cos_i: float, eta: float) -> float:
    """Unpolarised reflectance of a dielectric interface, eta = n_t / n_i.

    cos_i < 0 means the light arrives from the other side (the eta side): the roles swap, as the
    dielectric material needs when a ray leaves the object. 1 under total internal reflection.
    """
    c = wp.clamp(cos_i, -1.0, 1.0)
    e = eta
    if c < 0.0:
        c = -c
        e = 1.0 / eta
    sin2_t = (1.0 - c * c) / (e * e)
    if sin2_t >= 1.0:
        return 1.0
    cos_t = wp.sqrt(1.0 - sin2_t)
    r_s = (c - e * cos_t) / (c + e * cos_t)
    r_p = (e * c - cos_t) / (e * c + cos_t)
    return 0.5 * (r_s * r_s + r_p * r_p)


@wp.func
def _fresnel_conductor_channel(cos_i: float, eta: float, k: float) -> float:
    n = wp.vec2(eta, k)
    q0_sq = normal_component_sq(cos_i, 1.0)
    q0 = c_sqrt(q0_sq)
    q = normal_component(q0_sq, 1.0, n)
    one = wp.vec2(1.0, 0.0)
    r_s, t_s, u_s = fresnel_amplitudes(q0, q, one, one, one)
    r_p, t_p, u_p = fresnel_amplitudes(q0, q, one, c_mul(n, n), n)
    return 0.5 * (c_abs2(r_s) + c_abs2(r_p))


@wp.func
def fresnel_conductor(cos_i: float, eta: wp.vec3, k: wp.vec3) -> wp.vec3:
    """Unpolarised reflectance per RGB channel of a conductor of relative index eta + i k.

    The side is irrelevant for an opaque conductor, so |cos_i| is used.
    """
    c = wp.min(wp.abs(cos_i), 1.0)
    return wp.vec3(_fresnel_conductor_channel(c, eta[0], k[0]),
                   _fresnel_conductor_channel(c, eta[1], k[1]),
                   _fresnel_conductor_channel(c, eta[2], k[2]))


# ---------------------------------------------------------------------------------------------
# Thin film: n0 | film n1, thickness d | substrate n2


@wp.struct
class PolarisedFilm:
    """Wavelength-independent part of the Airy sum for one polarisation."""
    r01: wp.vec2
    r12: wp.vec2
    t01t10_sq: float      # |t01 t10|²: intensity coupled in and back out, for the incoherent sum
    transmit_sq: float    # |t01 t12|² × the substrate's flux factor: T without the film terms


@wp.struct
class FilmInterfaces:
    """Everything about a film that does not depend on wavelength or thickness (no dispersion):
    computed once per shading point, then reused for every wavelength sample."""
    s: PolarisedFilm
    p: PolarisedFilm
    q1: wp.vec2


@wp.func
def _polarised_film(q0: wp.vec2, q1: wp.vec2, q2: wp.vec2, w0: wp.vec2, w1: wp.vec2, w2: wp.vec2,
                    nn01: wp.vec2, nn12: wp.vec2, flux: float) -> PolarisedFilm:
    r01, t01, t10 = fresnel_amplitudes(q0, q1, w0, w1, nn01)
    r12, t12, t21 = fresnel_amplitudes(q1, q2, w1, w2, nn12)
    f = PolarisedFilm()
    f.r01 = r01
    f.r12 = r12
    f.t01t10_sq = c_abs2(c_mul(t01, t10))
    f.transmit_sq = c_abs2(c_mul(t01, t12)) * flux
    return f


@wp.func
def thin_film_interfaces(cos0: float, n0: float, n1: wp.vec2, n2: wp.vec2) -> FilmInterfaces:
    """Fresnel amplitudes of both interfaces, s and p. cos0 in [0, 1] (clamped), n0 real."""
    c = wp.clamp(cos0, 0.0, 1.0)
    q0_sq = normal_component_sq(c, n0)
    q0 = c_sqrt(q0_sq)
    q1 = normal_component(q0_sq, n0, n1)
    q2 = normal_component(q0_sq, n0, n2)
    one = wp.vec2(1.0, 0.0)
    e0 = wp.vec2(n0 * n0, 0.0)
    e1 = c_mul(n1, n1)
    e2 = c_mul(n2, n2)
    # Energy flux along the normal (Poynting) relative to the incident one; 0 when the substrate
    # wave is evanescent. s: Re(q2)/Re(q0); p: Re(q2 conj(n2)/n2)/Re(q0) (n0 real).
    inv_q0 = 1.0 / wp.max(q0[0], _TINY)
    flux_s = wp.max(q2[0], 0.0) * inv_q0
    flux_p = wp.max(c_div(c_mul(q2, c_conj(e2)), wp.vec2(c_abs2(n2), 0.0))[0], 0.0) * inv_q0
    f = FilmInterfaces()
    f.s = _polarised_film(q0, q1, q2, one, one, one, one, one, flux_s)
    f.p = _polarised_film(q0, q1, q2, e0, e1, e2, n0 * n1, c_mul(n1, n2), flux_p)
    f.q1 = q1
    return f


@wp.func
def sinc(x: float) -> float:
    """sin(x)/x, with its Taylor series where the quotient would lose precision."""
    if wp.abs(x) < 1.0e-3:
        return 1.0 - x * x / 6.0
    return wp.sin(x) / x


@wp.func
def _airy(f: PolarisedFilm, e: wp.vec2, e_abs: float, coherence: float) -> wp.vec2:
    """(R, T) of one polarisation given the round-trip factor e = exp(2iβ) and its modulus."""
    den = wp.vec2(1.0, 0.0) + c_mul(f.r01, c_mul(f.r12, e))
    inv_den = 1.0 / wp.max(c_abs2(den), _TINY)
    r_coh = c_abs2(f.r01 + c_mul(f.r12, e)) * inv_den
    t_coh = f.transmit_sq * e_abs * inv_den
    if coherence == 1.0:   # monochromatic: skip the incoherent sum
        return wp.vec2(wp.min(r_coh, 1.0), wp.min(t_coh, 1.0))
    # Incoherent: add the beams' intensities (geometric series in R10 R12 |e|²).
    R01 = c_abs2(f.r01)
    R12 = c_abs2(f.r12)
    a = e_abs * e_abs
    inv_inc = 1.0 / wp.max(1.0 - R01 * R12 * a, _TINY)
    r_inc = wp.min(R01 + f.t01t10_sq * R12 * a * inv_inc, 1.0)
    t_inc = wp.min(f.transmit_sq * e_abs * inv_inc, 1.0)
    # Roundoff, and sinc's negative lobes (a few % of the fringe contrast), must stay physical.
    return wp.vec2(wp.clamp(r_inc + coherence * (r_coh - r_inc), 0.0, 1.0),
                   wp.clamp(t_inc + coherence * (t_coh - t_inc), 0.0, 1.0))


@wp.func
def film_RT(f: FilmInterfaces, lambda_nm: float, d_nm: float, band_nm: float) -> wp.vec2:
    """(R, T), averaged over s and p, at one wavelength, averaged over a band of width band_nm."""
    # Round trip in the film, in cycles: 2 q1 d / λ (real part: phase, imaginary part: decay).
    cycles = 2.0 * f.q1[0] * d_nm / lambda_nm
    phase = 2.0 * wp.pi * (cycles - wp.floor(cycles))
    e_abs = wp.exp(-4.0 * wp.pi * f.q1[1] * d_nm / lambda_nm)
    e = e_abs * c_expi(phase)
    coherence = sinc(wp.pi * cycles * band_nm / lambda_nm)
    return 0.5 * (_airy(f.s, e, e_abs, coherence) + _airy(f.p, e, e_abs, coherence))


@wp.func
def thin_film_RT(cos0: float, lambda_nm: float, n0: float, n1: wp.vec2, n2: wp.vec2, d_nm: float,
                 band_nm: float) -> wp.vec2:
    """(R, T) of a film n1 (thickness d_nm) between n0 (real) and substrate n2, unpolarised.

    T is the power entering the substrate (with the n2 cos θ2 / n0 cos θ0 flux factor, 0 when the
    substrate wave is evanescent); R + T = 1 when film and substrate are lossless.
    band_nm: the spectral width this sample stands for (0: monochromatic; see module docstring).
    """
    return film_RT(thin_film_interfaces(cos0, n0, n1, n2), lambda_nm, d_nm, band_nm)


@wp.func
def thin_film_R(cos0: float, lambda_nm: float, n0: float, n1: wp.vec2, n2: wp.vec2, d_nm: float,
                band_nm: float) -> float:
    """Unpolarised reflectance of the film (see :func:`thin_film_RT`)."""
    return thin_film_RT(cos0, lambda_nm, n0, n1, n2, d_nm, band_nm)[0]


# ---------------------------------------------------------------------------------------------
# Spectrum → RGB on the device

RGB3_R, RGB3_G, RGB3_B = (wp.constant(x) for x in spectral.RGB3_WAVELENGTHS_NM)


@wp.struct
class RgbWeightTable:
    """w(λ) in 1/nm on a regular grid (see :func:`renderer.spectral.rgb_weight_table`)."""
    w: wp.array(dtype=wp.vec3)
    lambda_min: float
    step: float


def make_rgb_weight_table(device: str | None = None) -> RgbWeightTable:
    """Upload the colour-matching table. The caller keeps the returned struct alive while kernels use it."""
    w, lambda_min, step = spectral.rgb_weight_table()
    table = RgbWeightTable()
    table.w = wp.array(w, dtype=wp.vec3, device=device)
    table.lambda_min = lambda_min
    table.step = step
    return table


@wp.func
def rgb_weight(table: RgbWeightTable, lambda_nm: float) -> wp.vec3:
    x = (lambda_nm - table.lambda_min) / table.step
    last = table.w.shape[0] - 1
    i = wp.clamp(int(wp.floor(x)), 0, last - 1)
    t = wp.clamp(x - float(i), 0.0, 1.0)
    return (1.0 - t) * table.w[i] + t * table.w[i + 1]


@wp.func
def thin_film_rgb_sampled(cos0: float, n0: float, n1: wp.vec2, n2: wp.vec2, d_nm: float, n_samples: int,
                          u_jitter: float, table: RgbWeightTable):
    """Linear-sRGB (reflectance, transmittance) of the film from n_samples stratified wavelengths.

    λ_i = λ_min + (i + u_jitter)·Δ over the table's range, Δ = range / n_samples: with u_jitter
    uniform in [0, 1) per pixel sample, the sum of R(λ_i) w(λ_i) Δ is an unbiased estimate of the
    CIE integral (exactly white for R ≡ 1 in expectation), so the error is noise that falls with
    spp. Samples are monochromatic (band 0) to keep it unbiased: a film so thick that its fringes
    are finer than a stratum gives noise around the incoherent colour, never a false colour.
    """
    f = thin_film_interfaces(cos0, n0, n1, n2)
    step = table.step * float(table.w.shape[0] - 1) / float(n_samples)
    r = wp.vec3(0.0)
    t = wp.vec3(0.0)
    for i in range(n_samples):
        lam = table.lambda_min + (float(i) + u_jitter) * step
        rt = film_RT(f, lam, d_nm, 0.0)
        w = rgb_weight(table, lam) * step
        r += rt[0] * w
        t += rt[1] * w
    return r, t


@wp.func
def thin_film_rgb3(cos0: float, n0: float, n1: wp.vec2, n2: wp.vec2, d_nm: float):
    """The seed's mode: (R, T) at 650, 510 and 475 nm used directly as R, G, B (monochromatic)."""
    f = thin_film_interfaces(cos0, n0, n1, n2)
    red = film_RT(f, RGB3_R, d_nm, 0.0)
    green = film_RT(f, RGB3_G, d_nm, 0.0)
    blue = film_RT(f, RGB3_B, d_nm, 0.0)
    return wp.vec3(red[0], green[0], blue[0]), wp.vec3(red[1], green[1], blue[1])


# ---------------------------------------------------------------------------------------------
# numpy wrappers: launch the same device functions on the CPU (tests, benchmarks, tools)


@wp.kernel
def _rt_kernel(cos0: wp.array(dtype=float), lam: wp.array(dtype=float), n0: wp.array(dtype=float),
               n1: wp.array(dtype=wp.vec2), n2: wp.array(dtype=wp.vec2), d: wp.array(dtype=float),
               band_nm: float, out: wp.array(dtype=wp.vec2)):
    i = wp.tid()
    out[i] = thin_film_RT(cos0[i], lam[i], n0[i], n1[i], n2[i], d[i], band_nm)


@wp.kernel
def _rgb_quadrature_kernel(cos0: wp.array(dtype=float), n0: wp.array(dtype=float), n1: wp.array(dtype=wp.vec2),
                           n2: wp.array(dtype=wp.vec2), d: wp.array(dtype=float), lam: wp.array(dtype=float),
                           weights: wp.array(dtype=wp.vec3), band_nm: float, out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    f = thin_film_interfaces(cos0[i], n0[i], n1[i], n2[i])
    rgb = wp.vec3(0.0)
    for j in range(lam.shape[0]):
        rgb += film_RT(f, lam[j], d[i], band_nm)[0] * weights[j]
    out[i] = rgb


@wp.kernel
def _rgb3_kernel(cos0: wp.array(dtype=float), n0: wp.array(dtype=float), n1: wp.array(dtype=wp.vec2),
                 n2: wp.array(dtype=wp.vec2), d: wp.array(dtype=float), out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    r, t = thin_film_rgb3(cos0[i], n0[i], n1[i], n2[i], d[i])
    out[i] = r


@wp.kernel
def _rgb_sampled_kernel(cos0: wp.array(dtype=float), n0: wp.array(dtype=float), n1: wp.array(dtype=wp.vec2),
                        n2: wp.array(dtype=wp.vec2), d: wp.array(dtype=float), u: wp.array(dtype=float),
                        n_samples: int, table: RgbWeightTable, out_r: wp.array(dtype=wp.vec3),
                        out_t: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    r, t = thin_film_rgb_sampled(cos0[i], n0[i], n1[i], n2[i], d[i], n_samples, u[i], table)
    out_r[i] = r
    out_t[i] = t


def _complex_vec2(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=np.complex128).ravel()
    return np.stack([x.real, x.imag], axis=-1).astype(np.float32)


def _film_inputs(cos_theta, eta_outer, eta_film, eta_inner, thickness_nm, *extra):
    """Broadcast the film parameters and put them on the CPU device as flat arrays."""
    eta_outer = np.asarray(eta_outer)
    if np.iscomplexobj(eta_outer) and np.any(np.imag(eta_outer) != 0):
        raise ValueError("the outer medium must be lossless (real eta_outer)")
    arrays = np.broadcast_arrays(np.asarray(cos_theta, np.float64), np.real(eta_outer).astype(np.float64),
                                 np.asarray(eta_film), np.asarray(eta_inner),
                                 np.asarray(thickness_nm, np.float64), *(np.asarray(e, np.float64) for e in extra))
    shape = arrays[0].shape
    cos0, n0, n1, n2, d, *rest = arrays

    def flat(a: np.ndarray) -> wp.array:
        return wp.array(np.ascontiguousarray(a, dtype=np.float32).ravel(), dtype=float, device="cpu")

    inputs = [flat(cos0), flat(n0), wp.array(_complex_vec2(n1), dtype=wp.vec2, device="cpu"),
              wp.array(_complex_vec2(n2), dtype=wp.vec2, device="cpu"), flat(d)]
    return shape, inputs, [flat(a) for a in rest]


def thin_film_reflectance_transmittance(cos_theta, wavelength_nm, eta_outer, eta_film, eta_inner, thickness_nm,
                                        band_nm: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(R, T) arrays, broadcast over all arguments (eta_film and eta_inner may be complex, n + ik)."""
    shape, (cos0, n0, n1, n2, d), (lam,) = _film_inputs(cos_theta, eta_outer, eta_film, eta_inner, thickness_nm,
                                                        wavelength_nm)
    out = wp.empty(cos0.shape[0], dtype=wp.vec2, device="cpu")
    wp.launch(_rt_kernel, dim=out.shape[0], inputs=[cos0, lam, n0, n1, n2, d, float(band_nm), out], device="cpu")
    rt = out.numpy().reshape(shape + (2,))
    return rt[..., 0], rt[..., 1]


def thin_film_reflectance(cos_theta, wavelength_nm, eta_outer, eta_film, eta_inner, thickness_nm,
                          band_nm: float = 0.0) -> np.ndarray:
    """Unpolarised thin-film reflectance, broadcast over all arguments (float32)."""
    return thin_film_reflectance_transmittance(cos_theta, wavelength_nm, eta_outer, eta_film, eta_inner,
                                               thickness_nm, band_nm)[0]


def thin_film_rgb(cos_theta, eta_outer, eta_film, eta_inner, thickness_nm, mode: str = "spectral:32") -> np.ndarray:
    """Linear-sRGB reflectance (..., 3) of the film under D65 (R ≡ 1 is exactly white).

    mode: ``"rgb3"`` (the seed's three wavelengths), ``"spectral:N"`` (N stratum midpoints, each
    averaging the interference over its stratum) or ``"reference"`` (every nm of 360–830).
    """
    shape, inputs, _ = _film_inputs(cos_theta, eta_outer, eta_film, eta_inner, thickness_nm)
    out = wp.empty(inputs[0].shape[0], dtype=wp.vec3, device="cpu")
    if mode == "rgb3":
        wp.launch(_rgb3_kernel, dim=out.shape[0], inputs=[*inputs, out], device="cpu")
    else:
        lam, weights, band = spectral.mode_wavelengths(mode)
        wp.launch(_rgb_quadrature_kernel, dim=out.shape[0],
                  inputs=[*inputs, wp.array(lam.astype(np.float32), dtype=float, device="cpu"),
                          wp.array(weights.astype(np.float32), dtype=wp.vec3, device="cpu"), float(band), out],
                  device="cpu")
    return out.numpy().reshape(shape + (3,))


def thin_film_rgb_jittered(cos_theta, eta_outer, eta_film, eta_inner, thickness_nm, u_jitter, n_samples: int,
                           table: RgbWeightTable | None = None) -> tuple[np.ndarray, np.ndarray]:
    """One evaluation of the renderer's estimator :func:`thin_film_rgb_sampled` per element:
    (reflectance, transmittance), each (..., 3). For tests and benchmarks."""
    shape, inputs, (u,) = _film_inputs(cos_theta, eta_outer, eta_film, eta_inner, thickness_nm, u_jitter)
    table = table if table is not None else make_rgb_weight_table("cpu")
    out_r = wp.empty(u.shape[0], dtype=wp.vec3, device="cpu")
    out_t = wp.empty(u.shape[0], dtype=wp.vec3, device="cpu")
    wp.launch(_rgb_sampled_kernel, dim=u.shape[0], inputs=[*inputs, u, int(n_samples), table, out_r, out_t],
              device="cpu")
    return out_r.numpy().reshape(shape + (3,)), out_t.numpy().reshape(shape + (3,))
