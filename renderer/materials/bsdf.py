"""The interface every material implements, in the local shading frame (z = shading normal).

- ``eval(b, wo, wi) -> vec3``: the BSDF value f (without the cosine); 0 for delta lobes.
- ``pdf(b, wo, wi) -> float``: solid-angle density with which ``sample`` picks ``wi``.
- ``sample(b, wo, u) -> BSDFSample``: a direction with its throughput weight f·|cos θi|/pdf.

``wo`` may lie below the surface (transmission, or the back of a two-sided material); each
material decides what that means. Parameters arrive already evaluated from textures in the rows
of ``BSDF.p`` (one row per parameter slot, in the order the material's ``SLOTS`` lists them).
"""
from __future__ import annotations

import warp as wp

from renderer.color.rgb_weights import RgbWeightTable

MAX_SLOTS = 16
Slots = wp.types.matrix(shape=(MAX_SLOTS, 3), dtype=wp.float32)


@wp.struct
class BSDF:
    kind: int
    p: Slots
    wavelength_u: float     # a per-sample random number for materials that sample wavelengths
    spectral: RgbWeightTable  # spectrum → RGB weights for those materials (the scene's, see device_scene)
    spectral_n: int         # wavelengths per evaluation; 0: the seed's three (rgb3)


@wp.struct
class BSDFSample:
    wi: wp.vec3
    weight: wp.vec3         # f * |cos θi| / pdf
    pdf: float              # 0 means the sample failed; meaningless for delta lobes
    specular: bool          # a delta lobe: skip MIS, NEE cannot reach it
    eta: float              # relative index crossed by a transmission (0 or 1: none)


@wp.func
def failed_sample() -> BSDFSample:
    s = BSDFSample()
    s.pdf = 0.0
    return s


@wp.func
def same_hemisphere(a: wp.vec3, b: wp.vec3) -> bool:
    return a[2] * b[2] > 0.0


@wp.func
def reflect_z(w: wp.vec3) -> wp.vec3:
    """Mirror reflection about the local normal."""
    return wp.vec3(-w[0], -w[1], w[2])


@wp.func
def refract(wi: wp.vec3, n: wp.vec3, eta: float) -> wp.vec4:
    """Refracted direction of wi (pointing away from the surface) through normal n; w = eta' or 0 under TIR."""
    cos_i = wp.dot(n, wi)
    e = eta
    nn = n
    if cos_i < 0.0:
        e = 1.0 / e
        cos_i = -cos_i
        nn = -n
    sin2_t = wp.max(0.0, 1.0 - cos_i * cos_i) / (e * e)
    if sin2_t >= 1.0:
        return wp.vec4(0.0)
    cos_t = wp.sqrt(1.0 - sin2_t)
    wt = -wi / e + nn * (cos_i / e - cos_t)
    return wp.vec4(wt[0], wt[1], wt[2], e)
