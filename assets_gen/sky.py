"""Clear-sky environment maps from the Preetham, Shirley & Smits (1999) analytic daylight model,
with the sun as data for a matching distant light (the sun disc is NOT in the map).

Sky: the Perez luminance distribution F(θ, γ) = (1 + A e^(B/cos θ))(1 + C e^(Dγ) + E cos²γ) for
Y, x and y, scaled by Preetham's zenith luminance Y_z(T, θs) and zenith chromaticities x_z, y_z
(the paper's Appendix A tables), θ the view's zenith angle and γ its angle to the sun. xyY is
converted to linear sRGB (D65, no adaptation). Below the horizon the map holds a uniform
Lambertian ground of albedo ``ground_albedo`` lit by this sky and the sun (0 = black).
Known properties of the model (Zotti, Wilkie & Purgathofer 2007): it is brighter than the CIE
clear sky (its diffuse horizontal illuminance is about twice the IES clear-sky formula at T = 3),
and near T = 2 the horizon band can outshine the circumsolar region.

Sun: the extraterrestrial spectrum taken as a 5778 K blackbody scaled to the solar illuminance
constant (128 klx), attenuated along Kasten & Young's air mass by Rayleigh scattering
(τ = 0.008735 λ^-4.08, λ in µm) and Ångström haze (β = 0.04608 T − 0.04586, α = 1.3), the
transmittances Preetham's Appendix uses (ozone and water vapour are left out). Its radiance is its
normal illuminance over the solid angle of a disc of angular radius 0.27°.

Units: pixel luminance (0.2126 R + 0.7152 G + 0.0722 B) is luminance in kcd/m², so a sky integral
of L cos θ over the upper hemisphere gives illuminance in klx; the sun's radiance in the manifest
uses the same units.

Frame: the map is written in the light's own frame, +z up as pbrt does; a y-up scene rotates it
with ``Rotate -90 1 0 0`` (light +z → world +y, light +y → world −z, +x stays). The sun's azimuth
φs is measured from +x towards +y in the light frame (from +x towards −z in the world).
Layouts (pixel (x, y), row y = 0 at the top of the file):
  lat-long, W = 2H: φ = 2π(x + 0.5)/W, θ = π(y + 0.5)/H, direction (sinθ cosφ, sinθ sinφ, cosθ);
  equal-area, W = H: (u, v) = ((x + 0.5)/W, (y + 0.5)/H) through Clarberg's octahedral equal-area
  map (pbrt-v4's EqualAreaSquareToSphere, through the renderer's own float32 implementation in
  renderer.sampling.equal_area), every pixel the same solid angle 4π/(W H).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from assets_gen.core import Generator, Job, Params, param, require
from assets_gen.solar_position import SunPosition, parse_local_time, sun_position

SUN_ANGULAR_RADIUS_DEG = 0.27
SOLAR_ILLUMINANCE_LUX = 128_000.0   # extraterrestrial solar illuminance constant (IES, ~127.5-128 klx)


def latlong_directions(height: int) -> np.ndarray:
    """Pixel-centre directions (H, 2H, 3) of a lat-long map."""
    w = 2 * height
    phi = 2.0 * np.pi * (np.arange(w) + 0.5) / w
    theta = np.pi * (np.arange(height) + 0.5) / height
    st = np.sin(theta)[:, None]
    return np.stack([st * np.cos(phi), st * np.sin(phi), np.broadcast_to(np.cos(theta)[:, None], (height, w))], -1)


def equal_area_directions(size: int) -> np.ndarray:
    """Pixel-centre directions (N, N, 3) of an equal-area square map (u along x, v along rows),
    through the renderer's own map, so the sky is written where the renderer will look it up."""
    from renderer.sampling.equal_area import square_to_sphere

    c = (np.arange(size) + 0.5) / size
    return square_to_sphere(np.stack(np.meshgrid(c, c, indexing="xy"), -1)).astype(np.float64)


# ---- Preetham 1999 -----------------------------------------------------------------------------

_PEREZ = {  # (slope on T, intercept) for A..E, Preetham et al. 1999, Appendix A.2
    "Y": ((0.1787, -1.4630), (-0.3554, 0.4275), (-0.0227, 5.3251), (0.1206, -2.5771), (-0.0670, 0.3703)),
    "x": ((-0.0193, -0.2592), (-0.0665, 0.0008), (-0.0004, 0.2125), (-0.0641, -0.8989), (-0.0033, 0.0452)),
    "y": ((-0.0167, -0.2608), (-0.0950, 0.0092), (-0.0079, 0.2102), (-0.0441, -1.6537), (-0.0109, 0.0529)),
}
_ZENITH_X = np.array([[0.00166, -0.00375, 0.00209, 0.0], [-0.02903, 0.06377, -0.03202, 0.00394],
                      [0.11693, -0.21196, 0.06052, 0.25886]])
_ZENITH_Y = np.array([[0.00275, -0.00610, 0.00317, 0.0], [-0.04214, 0.08970, -0.04153, 0.00516],
                      [0.15346, -0.26756, 0.06670, 0.26688]])


def _perez(coef: tuple, turbidity: float, cos_theta: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    A, B, C, D, E = (s * turbidity + c for s, c in coef)
    return (1.0 + A * np.exp(B / np.maximum(cos_theta, 1e-3))) * (1.0 + C * np.exp(D * gamma) + E * np.cos(gamma) ** 2)


def xyY_to_srgb(x: np.ndarray, y: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Linear sRGB (D65 white, IEC 61966-2-1 matrix) of CIE xyY."""
    X = x / y * Y
    Z = (1.0 - x - y) / y * Y
    m = np.array([[3.2404542, -1.5371385, -0.4985314], [-0.9692660, 1.8760108, 0.0415560],
                  [0.0556434, -0.2040259, 1.0572252]])
    return np.stack([X, Y, Z], -1) @ m.T


def sun_direction(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    """Unit vector towards the sun in the light frame (+z up, azimuth from +x towards +y)."""
    e, a = np.radians(elevation_deg), np.radians(azimuth_deg)
    return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


def sky_radiance(dirs: np.ndarray, sun: np.ndarray, turbidity: float) -> np.ndarray:
    """Preetham sky in linear sRGB (luminance in kcd/m²) for directions (..., 3); zero below the horizon."""
    theta_s = np.arccos(sun[2])
    cos_t = dirs[..., 2]
    gamma = np.arccos(np.clip(dirs @ sun, -1.0, 1.0))
    chi = (4.0 / 9.0 - turbidity / 120.0) * (np.pi - 2.0 * theta_s)
    Yz = (4.0453 * turbidity - 4.9710) * np.tan(chi) - 0.2155 * turbidity + 2.4192
    t = np.array([turbidity ** 2, turbidity, 1.0])
    th = np.array([theta_s ** 3, theta_s ** 2, theta_s, 1.0])
    zen = {"Y": Yz, "x": t @ _ZENITH_X @ th, "y": t @ _ZENITH_Y @ th}
    val = {k: zen[k] * _perez(_PEREZ[k], turbidity, cos_t, gamma)
           / _perez(_PEREZ[k], turbidity, np.array(1.0), np.array(theta_s)) for k in zen}
    rgb = xyY_to_srgb(val["x"], val["y"], val["Y"])
    return np.where((cos_t > 0)[..., None], np.maximum(rgb, 0.0), 0.0)


def sun_light(sun: np.ndarray, turbidity: float) -> dict[str, Any]:
    """The sun after the atmosphere: direction, linear sRGB radiance (kcd/m² luminance units),
    solid angle and normal illuminance."""
    import colour

    elevation = np.degrees(np.arcsin(sun[2]))
    air_mass = 1.0 / (sun[2] + 0.50572 * (elevation + 6.07995) ** -1.6364)   # Kasten & Young 1989
    shape = colour.SpectralShape(380, 780, 5)
    lam = shape.wavelengths / 1000.0                                          # µm
    tau = 0.008735 * lam ** -4.08 + (0.04608 * turbidity - 0.04586) * lam ** -1.3
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
    planck = colour.sd_blackbody(5778.0, shape).values
    Y_top = (planck * cmfs.values[:, 1]).sum()
    xyz = (planck * np.exp(-air_mass * tau))[:, None] * cmfs.values
    xyz = xyz.sum(0) / Y_top * SOLAR_ILLUMINANCE_LUX / 1000.0                # klx at normal incidence
    omega = 2.0 * np.pi * (1.0 - np.cos(np.radians(SUN_ANGULAR_RADIUS_DEG)))
    s = xyz.sum()
    rgb_irradiance = xyY_to_srgb(np.array(xyz[0] / s), np.array(xyz[1] / s), np.array(xyz[1]))
    return {"direction_light_frame": sun, "direction_world_y_up": np.array([sun[0], sun[2], -sun[1]]) + 0.0,
            "angular_radius_deg": SUN_ANGULAR_RADIUS_DEG, "solid_angle_sr": omega,
            "normal_illuminance_lux": float(xyz[1] * 1000.0), "air_mass": float(air_mass),
            "rgb_irradiance": rgb_irradiance, "rgb_radiance": rgb_irradiance / omega}


def diffuse_horizontal_klx(rgb: np.ndarray, dirs: np.ndarray, solid_angle: np.ndarray) -> float:
    """∫ L cos θ dω over the upper hemisphere (klx, from the map's luminance)."""
    lum = rgb[..., 0] * 0.2126 + rgb[..., 1] * 0.7152 + rgb[..., 2] * 0.0722
    return float((lum * np.maximum(dirs[..., 2], 0.0) * solid_angle).sum())


@dataclass(frozen=True)
class SkyParams(Params):
    elevation_deg: float = param(45.0, "sun elevation above the horizon, degrees (unless --date is given)")
    azimuth_deg: float = param(0.0, "sun azimuth, light frame +x towards +y, degrees (unless --date is given)")
    date: str = param("", "YYYY-MM-DD: take the sun's position from date, time and place (Meeus) instead")
    local_time: str = param("12:00", "local clock time HH:MM[:SS] with --date")
    utc_offset_h: float = param(0.0, "hours the local clock is ahead of UTC, with --date")
    latitude_deg: float = param(0.0, "latitude (north positive), degrees, with --date")
    longitude_deg: float = param(0.0, "longitude (east positive), degrees, with --date")
    north_azimuth_deg: float = param(90.0, "light-frame azimuth of geographic north (+x towards +y); "
                                   "bearings add to it, degrees")
    turbidity: float = param(3.0, "atmospheric turbidity, 2..10")
    resolution: int = param(512, "map height in pixels")
    layout: str = param("both", "which maps to write", choices=("both", "latlong", "equal-area"))
    ground_albedo: float = param(0.0, "below-horizon Lambertian ground albedo, 0 = black")

    def validate(self) -> None:
        require(0.5 <= self.elevation_deg <= 90.0,
                f"sun elevation must be 0.5..90 deg (Preetham has no night), got {self.elevation_deg}")
        require(2.0 <= self.turbidity <= 10.0,
                f"turbidity must be 2..10 (the model's fitted range), got {self.turbidity}")
        require(8 <= self.resolution <= 4096,
                f"resolution must be 8..4096 (memory grows with the pixel count: 1.6 GB at 2048), got {self.resolution}")
        require(self.layout in ("both", "latlong", "equal-area"),
                f"layout must be both, latlong or equal-area, got {self.layout!r}")
        require(0.0 <= self.ground_albedo <= 1.0, f"ground albedo must be 0..1, got {self.ground_albedo}")
        if self.date:
            elevation = self.sun().elevation_deg
            require(elevation >= 0.5, f"the sun is {elevation:.3g} deg high at {self.date} {self.local_time} "
                                      "there (the sky model needs at least 0.5 deg)")

    def sun(self) -> SunPosition:
        """The sun's elevation and compass azimuth for --date, --local-time and the place."""
        when = parse_local_time(self.date, self.local_time, self.utc_offset_h)
        return sun_position(when, self.latitude_deg, self.longitude_deg)

    def sun_angles(self) -> tuple[float, float]:
        """(elevation, light-frame azimuth) in degrees: given, or from the date."""
        if not self.date:
            return self.elevation_deg, self.azimuth_deg
        pos = self.sun()
        return pos.elevation_deg, light_azimuth(pos.azimuth_deg, self.north_azimuth_deg)


def light_azimuth(bearing_deg: float, north_azimuth_deg: float) -> float:
    """The light-frame azimuth of a compass bearing. pbrt's world is left-handed (LookAt puts
    up × forward on the image's right), so seen from above in a render the light frame's azimuth
    turns clockwise, as bearings do: a bearing adds to north's azimuth."""
    return (north_azimuth_deg + bearing_deg) % 360.0


def write(job: Job) -> list[str]:
    """``sky_latlong.exr`` (2R × R) and/or ``sky_equalarea.exr`` (R × R); the manifest also holds the
    sun and the sky's illuminances. The model is deterministic: the seed is recorded but draws nothing."""
    from renderer.io.images import write_exr

    p = job.params
    (elevation_deg, azimuth_deg), turbidity, resolution, layout = p.sun_angles(), p.turbidity, p.resolution, p.layout
    sun = sun_direction(elevation_deg, azimuth_deg)
    light = sun_light(sun, turbidity)
    ea_dirs = equal_area_directions(resolution)
    ea = sky_radiance(ea_dirs, sun, turbidity)
    e_dh = diffuse_horizontal_klx(ea, ea_dirs, np.full(ea.shape[:2], 4.0 * np.pi / resolution ** 2))
    e_sun = light["rgb_irradiance"] * sun[2]
    horizontal = np.einsum("ijk,ij->k", ea, np.maximum(ea_dirs[..., 2], 0)) * 4.0 * np.pi / resolution ** 2 + e_sun
    ground = p.ground_albedo / np.pi * horizontal                                # Lambertian ground radiance
    maps = {}
    if layout in ("both", "equal-area"):
        maps["sky_equalarea.exr"] = np.where((ea_dirs[..., 2] > 0)[..., None], ea, ground)
    if layout in ("both", "latlong"):
        ll_dirs = latlong_directions(resolution)
        maps["sky_latlong.exr"] = np.where((ll_dirs[..., 2] > 0)[..., None],
                                           sky_radiance(ll_dirs, sun, turbidity), ground)
    info = {"sun": light, "solar_position": {"elevation_deg": elevation_deg, "azimuth_deg": azimuth_deg,
                                             "compass_azimuth_deg": p.sun().azimuth_deg if p.date else None,
                                             "from": "Meeus (1998) chs. 12, 13, 25" if p.date else "given"},
            "sky": {"diffuse_horizontal_illuminance_lux": e_dh * 1000.0,
                                  "global_horizontal_illuminance_lux": e_dh * 1000.0
                                  + light["normal_illuminance_lux"] * sun[2],
                                  "ground_rgb_radiance": ground, "rgb_irradiance_horizontal": horizontal},
            "units": "pixel luminance in kcd/m^2 (linear sRGB); the sun disc is not in the map",
            "frame": "light frame +z up; in a y-up scene use Rotate -90 1 0 0",
            "sun_distant_light": "LightSource \"distant\" with \"point3 from\" = direction_world_y_up, "
                                 "\"rgb L\" = rgb_irradiance (a distant light's L is the irradiance it "
                                 f"delivers), \"float angularradius\" [{SUN_ANGULAR_RADIUS_DEG}]"}
    for name, img in maps.items():
        write_exr(job.stage / name, img.astype(np.float32))
    job.note(**info)
    return sorted(maps)


GENERATOR = Generator("sky", "Preetham clear-sky HDR environment map (EXR) and matching sun", SkyParams, write, __doc__)
