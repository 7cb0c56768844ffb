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
reduced modulo one cycle before the cosine, so float32 keeps ~1e-3 rad of absolute phase accuracy."""
from __future__ import annotations

import warp as wp

from renderer.color import spectral
from renderer.color.rgb_weights import RgbWeightTable, rgb_weight
from renderer.optics.complex import _TINY, c_abs2, c_conj, c_div, c_expi, c_mul, c_sqrt
from renderer.optics.fresnel import fresnel_amplitudes, normal_component, normal_component_sq


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


RGB3_R, RGB3_G, RGB3_B = (wp.constant(x) for x in spectral.RGB3_WAVELENGTHS_NM)


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
