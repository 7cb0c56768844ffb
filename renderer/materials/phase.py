"""The Henyey–Greenstein phase function of a scattering medium (the layered slab's), with
directions as pbrt-v4 passes them: ``wo`` and ``wi`` both point away from the scattering point,
so forward scattering is wi = -wo. Sampling is exact (pdf = phase value)."""
from __future__ import annotations

import warp as wp

from renderer.sampling.frames import frame_from_normal, to_world
from renderer.vecmath import PI

#: pbrt clamps |g| below 1, where the lobe would be a delta.
G_MAX = wp.constant(0.99)


@wp.func
def hg_phase(wo: wp.vec3, wi: wp.vec3, g: float) -> float:
    """p(wo, wi) = (1 - g²) / (4π (1 + g² - 2 g cos θ)^3/2), θ the deflection from -wo to wi."""
    gc = wp.clamp(g, -G_MAX, G_MAX)
    mu = -wp.dot(wo, wi)
    d = 1.0 + gc * gc - 2.0 * gc * mu
    return (1.0 - gc * gc) / (4.0 * PI * d * wp.sqrt(wp.max(d, 0.0)))


@wp.func
def hg_sample(wo: wp.vec3, g: float, u: wp.vec2) -> wp.vec3:
    """A direction wi distributed as hg_phase(wo, ·) (inverse of its cosine CDF)."""
    gc = wp.clamp(g, -G_MAX, G_MAX)
    mu = 1.0 - 2.0 * u[0]
    if wp.abs(gc) >= 1.0e-3:
        s = (1.0 - gc * gc) / (1.0 - gc + 2.0 * gc * u[0])
        mu = (1.0 + gc * gc - s * s) / (2.0 * gc)
    mu = wp.clamp(mu, -1.0, 1.0)
    sin_t = wp.sqrt(wp.max(0.0, 1.0 - mu * mu))
    phi = 2.0 * PI * u[1]
    return to_world(frame_from_normal(-wo), wp.vec3(sin_t * wp.cos(phi), sin_t * wp.sin(phi), mu))
