"""numpy wrappers: launch the device optics on the CPU for tests, benchmarks and tools."""
from __future__ import annotations

import numpy as np
import warp as wp

from renderer.color import spectral
from renderer.color.rgb_weights import RgbWeightTable, make_rgb_weight_table
from renderer.optics.multilayer import multilayer_RT, multilayer_rgb_sampled
from renderer.optics.thin_film import film_RT, thin_film_interfaces, thin_film_RT, thin_film_rgb3, thin_film_rgb_sampled

wp.set_module_options({"fast_math": False, "enable_backward": False})


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


@wp.kernel
def _stack_rt_kernel(cos0: wp.array(dtype=float), lam: wp.array(dtype=float), n0: float, n_sub: wp.vec2,
                     layers: wp.array(dtype=wp.vec4), out: wp.array(dtype=wp.vec2)):
    i = wp.tid()
    out[i] = multilayer_RT(cos0[i], lam[i], n0, n_sub, layers, 0, layers.shape[0], False, 1.0)


@wp.kernel
def _stack_rgb_quadrature_kernel(cos0: wp.array(dtype=float), n0: float, n_sub: wp.vec2,
                                 layers: wp.array(dtype=wp.vec4), lam: wp.array(dtype=float),
                                 weights: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    rgb = wp.vec3(0.0)
    for j in range(lam.shape[0]):
        rgb += multilayer_RT(cos0[i], lam[j], n0, n_sub, layers, 0, layers.shape[0], False, 1.0)[0] * weights[j]
    out[i] = rgb


@wp.kernel
def _stack_rgb_sampled_kernel(cos0: wp.array(dtype=float), n0: float, n_sub: wp.vec2,
                              layers: wp.array(dtype=wp.vec4), u: wp.array(dtype=float), n_samples: int,
                              table: RgbWeightTable, out_r: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    r, t = multilayer_rgb_sampled(cos0[i], n0, n_sub, layers, 0, layers.shape[0], False, 1.0, n_samples, u[i],
                                  table)
    out_r[i] = r


def stack_layers(eta, k, thickness_nm, cauchy_b=None) -> tuple[float, np.ndarray, np.ndarray]:
    """(outer index, substrate n + ik as (re, im), layer rows (L, 4)) of a stack given as eta/k of
    length L + 2 (outer, layers, substrate) and thickness_nm of length L; cauchy_b (µm², length L)
    adds dispersion to the layers, whose eta is then Cauchy's A."""
    eta = np.asarray(eta, np.float64).ravel()
    k = np.asarray(k, np.float64).ravel()
    d = np.asarray(thickness_nm, np.float64).ravel()
    n_layers = d.size
    if eta.size != n_layers + 2 or k.size != n_layers + 2:
        raise ValueError(f"eta and k need {n_layers + 2} values (outer, {n_layers} layers, substrate)")
    if k[0] != 0.0:
        raise ValueError("the outer medium must be lossless (k[0] = 0)")
    b = np.zeros(n_layers) if cauchy_b is None else np.broadcast_to(np.asarray(cauchy_b, np.float64), (n_layers,))
    rows = np.stack([eta[1:-1], b, k[1:-1], d], axis=-1).reshape(n_layers, 4)
    return float(eta[0]), np.array([eta[-1], k[-1]], np.float32), rows.astype(np.float32)


def _layer_array(rows: np.ndarray, n0: float) -> wp.array:
    """The layer rows on the CPU device; no layer is one 0 nm layer of the outer medium (a bare interface)."""
    return wp.array(rows if len(rows) else np.array([[n0, 0.0, 0.0, 0.0]], np.float32), dtype=wp.vec4, device="cpu")


def multilayer_reflectance_transmittance(cos_theta, wavelength_nm, eta, k, thickness_nm,
                                         cauchy_b=None) -> tuple[np.ndarray, np.ndarray]:
    """(R, T) of a stack (see :func:`stack_layers`), broadcast over cos_theta and wavelength_nm."""
    n0, n_sub, rows = stack_layers(eta, k, thickness_nm, cauchy_b)
    cos0, lam = np.broadcast_arrays(np.asarray(cos_theta, np.float64), np.asarray(wavelength_nm, np.float64))
    shape = cos0.shape
    flat = [wp.array(np.ascontiguousarray(a, np.float32).ravel(), dtype=float, device="cpu") for a in (cos0, lam)]
    out = wp.empty(flat[0].shape[0], dtype=wp.vec2, device="cpu")
    wp.launch(_stack_rt_kernel, dim=out.shape[0], inputs=[*flat, n0, wp.vec2(*n_sub), _layer_array(rows, n0), out],
              device="cpu")
    rt = out.numpy().reshape(shape + (2,))
    return rt[..., 0], rt[..., 1]


def multilayer_reflectance(cos_theta, wavelength_nm, eta, k, thickness_nm, cauchy_b=None) -> np.ndarray:
    """Unpolarised reflectance of a stack: eta, k of length L + 2 (outer, layers, substrate),
    thickness_nm of length L; broadcast over cos_theta and wavelength_nm (float32)."""
    return multilayer_reflectance_transmittance(cos_theta, wavelength_nm, eta, k, thickness_nm, cauchy_b)[0]


def multilayer_transmittance(cos_theta, wavelength_nm, eta, k, thickness_nm, cauchy_b=None) -> np.ndarray:
    """Power transmitted into the substrate (see :func:`multilayer_reflectance`)."""
    return multilayer_reflectance_transmittance(cos_theta, wavelength_nm, eta, k, thickness_nm, cauchy_b)[1]


def multilayer_rgb(cos_theta, eta, k, thickness_nm, mode: str = "spectral:32", cauchy_b=None) -> np.ndarray:
    """Linear-sRGB reflectance (..., 3) of a stack under D65 at monochromatic quadrature points:
    ``rgb3``, ``spectral:N`` (stratum midpoints) or ``reference`` (every nm)."""
    n0, n_sub, rows = stack_layers(eta, k, thickness_nm, cauchy_b)
    cos0 = np.asarray(cos_theta, np.float64)
    lam, weights, _ = spectral.mode_wavelengths(mode)
    out = wp.empty(cos0.size, dtype=wp.vec3, device="cpu")
    wp.launch(_stack_rgb_quadrature_kernel, dim=out.shape[0],
              inputs=[wp.array(cos0.astype(np.float32).ravel(), dtype=float, device="cpu"), n0, wp.vec2(*n_sub),
                      _layer_array(rows, n0), wp.array(lam.astype(np.float32), dtype=float, device="cpu"),
                      wp.array(weights.astype(np.float32), dtype=wp.vec3, device="cpu"), out], device="cpu")
    return out.numpy().reshape(cos0.shape + (3,))


def multilayer_rgb_jittered(cos_theta, eta, k, thickness_nm, u_jitter, n_samples: int, cauchy_b=None,
                            table: RgbWeightTable | None = None) -> np.ndarray:
    """One evaluation of the renderer's stack estimator :func:`multilayer_rgb_sampled` per element
    of the broadcast (cos_theta, u_jitter): linear-sRGB reflectance (..., 3). For benchmarks."""
    n0, n_sub, rows = stack_layers(eta, k, thickness_nm, cauchy_b)
    cos0, u = np.broadcast_arrays(np.asarray(cos_theta, np.float64), np.asarray(u_jitter, np.float64))
    flat = [wp.array(np.ascontiguousarray(a, np.float32).ravel(), dtype=float, device="cpu") for a in (cos0, u)]
    table = table if table is not None else make_rgb_weight_table("cpu")
    out = wp.empty(flat[0].shape[0], dtype=wp.vec3, device="cpu")
    wp.launch(_stack_rgb_sampled_kernel, dim=out.shape[0],
              inputs=[flat[0], n0, wp.vec2(*n_sub), _layer_array(rows, n0), flat[1], int(n_samples), table, out],
              device="cpu")
    return out.numpy().reshape(cos0.shape + (3,))
