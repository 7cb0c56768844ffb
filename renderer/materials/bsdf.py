"""The interface every material implements, in the local shading frame (z = shading normal).

- ``eval_pdf(b, wo, wi) -> BSDFEval``: the BSDF value f (without the cosine; 0 for delta lobes)
  and the solid-angle density with which ``sample`` picks ``wi``, computed together because they
  share most of their work (pbrt's ``f`` + ``PDF``, Mitsuba's ``eval_pdf``).
- ``sample(b, wo, u) -> BSDFSample``: a direction with its throughput weight f·|cos θi|/pdf and
  the lobe it came from (``flags``, pbrt's ``BxDFFlags``).

``wo`` may lie below the surface (transmission, or the back of a two-sided material); each
material decides what that means. Parameters arrive already evaluated from their textures in the
rows of ``BSDF.p``, read by name (``b.p[SLOT.roughness]``); bool parameters are bits of
``BSDF.flags`` (``b.flags & FLAG.thin``), see :mod:`renderer.parameters`.
"""
from __future__ import annotations

import warp as wp

from renderer.color.rgb_weights import RgbWeightTable

MAX_SLOTS = 16
Slots = wp.types.matrix(shape=(MAX_SLOTS, 3), dtype=wp.float32)
#: ``BSDF.flags`` bits below this one are a material's declared bool parameters; a module may use
#: the bits from here up for values it derives itself (e.g. "reflectance was given").
FIRST_DERIVED_FLAG = 1 << 16

# Lobe flags of a sample, as pbrt-v4's BxDFFlags: which side wi lies on and what kind of lobe.
REFLECTION = wp.constant(1)
TRANSMISSION = wp.constant(2)
DIFFUSE = wp.constant(4)
GLOSSY = wp.constant(8)
SPECULAR = wp.constant(16)


@wp.struct
class BSDF:
    kind: int
    p: Slots
    flags: int              # the material's bool parameters (and derived bits), one bit each
    wavelength_u: float     # a per-sample random number for materials that sample wavelengths
    spectral: RgbWeightTable  # spectrum → RGB weights for those materials (the scene's, see device.scene)
    spectral_n: int         # wavelengths per evaluation; 0: the seed's three (rgb3)
    layers: wp.array(dtype=wp.vec4)  # the scene's layer table (renderer.materials.stack)
    layer_first: int        # this material's first row in it
    layer_count: int        # and its number of rows; 0: no stack
    table_first: int        # its baked table in layers (renderer.optics.angular_table, .dispersion); 0: none


@wp.struct
class BSDFEval:
    f: wp.vec3              # the BSDF value, without the cosine
    pdf: float              # the density of sample() at wi (solid angle)


@wp.struct
class BSDFSample:
    wi: wp.vec3
    weight: wp.vec3         # f * |cos θi| / pdf
    pdf: float              # 0 means the sample failed; meaningless for delta lobes
    flags: int              # REFLECTION or TRANSMISSION, and DIFFUSE, GLOSSY or SPECULAR (a delta lobe:
                            # MIS is skipped, next-event estimation cannot reach it)
    eta: float              # relative index crossed by a transmission (0 or 1: none)


@wp.func
def failed_sample() -> BSDFSample:
    s = BSDFSample()
    s.pdf = 0.0
    return s


@wp.func
def side(wo: wp.vec3, wi: wp.vec3) -> int:
    """REFLECTION when wi lies on wo's side of the surface, else TRANSMISSION."""
    return wp.where(wo[2] * wi[2] > 0.0, REFLECTION, TRANSMISSION)


@wp.func
def delta_sample(wi: wp.vec3, weight: wp.vec3, pdf: float, flags: int) -> BSDFSample:
    """A sample of a delta lobe (``flags`` should include SPECULAR): its weight is given directly."""
    s = BSDFSample()
    s.wi = wi
    s.weight = weight
    s.pdf = pdf
    s.flags = flags
    return s


@wp.func
def sampled(wo: wp.vec3, wi: wp.vec3, ev: BSDFEval, lobe: int) -> BSDFSample:
    """A sampled direction of a non-delta lobe finished from its ``eval_pdf``: weight f |cos θi| / pdf."""
    if ev.pdf <= 0.0:
        return failed_sample()
    s = BSDFSample()
    s.wi = wi
    s.pdf = ev.pdf
    s.weight = ev.f * (wp.abs(wi[2]) / ev.pdf)
    s.flags = lobe | side(wo, wi)
    return s


@wp.func
def same_hemisphere(a: wp.vec3, b: wp.vec3) -> bool:
    return a[2] * b[2] > 0.0


@wp.func
def signed_z(w: wp.vec3, sgn: float) -> wp.vec3:
    """w with its z multiplied by sgn (±1): how two-sided lobes bring wo above the surface."""
    return wp.vec3(w[0], w[1], w[2] * sgn)


@wp.func
def reflect_z(w: wp.vec3) -> wp.vec3:
    """Mirror reflection about the local normal."""
    return wp.vec3(-w[0], -w[1], w[2])


@wp.func
def refract(wi: wp.vec3, n: wp.vec3, eta: float) -> wp.vec4:
    """Refracted direction of wi (pointing away from the surface) through normal n; w = eta' or 0 under TIR."""
    cos_i = wp.dot(n, wi)
    eta_rel = eta
    nn = n
    if cos_i < 0.0:
        eta_rel = 1.0 / eta_rel
        cos_i = -cos_i
        nn = -n
    sin2_t = wp.max(0.0, 1.0 - cos_i * cos_i) / (eta_rel * eta_rel)
    if sin2_t >= 1.0:
        return wp.vec4(0.0)
    cos_t = wp.sqrt(1.0 - sin2_t)
    wt = -wi / eta_rel + nn * (cos_i / eta_rel - cos_t)
    return wp.vec4(wt[0], wt[1], wt[2], eta_rel)
