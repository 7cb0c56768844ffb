"""Where the sun stands for a date, a local time and a place, so a scene's sky and sun follow a
time of day written in its recipe instead of a hand-picked elevation.

Meeus, *Astronomical Algorithms* (2nd ed. 1998): the Sun's apparent longitude from the
low-accuracy theory of chapter 25 (about 0.01 deg), the obliquity with the nutation correction
of the same chapter, Greenwich mean sidereal time from chapter 12 (eq. 12.4), and the horizontal
coordinates of chapter 13. Time is taken as UT for both (TT - UT, about 70 s today, moves the
sun by under 0.3 arc minutes). Elevation is geometric (no refraction: the renderer's atmosphere
has none either).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone

from assets_gen.core import GeneratorError, require


@dataclass(frozen=True)
class SunPosition:
    elevation_deg: float      # above the horizon
    azimuth_deg: float        # compass bearing: from north through east
    declination_deg: float
    right_ascension_deg: float


def julian_day(when: datetime) -> float:
    """Julian day of an aware datetime (Meeus ch. 7, through the Unix epoch JD 2440587.5)."""
    require(when.tzinfo is not None, "the time needs a UTC offset")
    return 2440587.5 + when.astimezone(timezone.utc).timestamp() / 86400.0


def parse_local_time(date: str, local_time: str, utc_offset_h: float) -> datetime:
    """``YYYY-MM-DD`` and ``HH:MM`` (or ``HH:MM:SS``) at ``utc_offset_h`` hours east of UTC."""
    try:
        d = datetime.fromisoformat(f"{date}T{local_time}")
    except ValueError:
        raise GeneratorError(f"date {date!r} / local time {local_time!r} must be YYYY-MM-DD and "
                             "HH:MM[:SS]") from None
    require(-14 <= utc_offset_h <= 14, f"UTC offset must be -14..14 h, got {utc_offset_h}")
    return d.replace(tzinfo=timezone(timedelta(hours=utc_offset_h)))


def sun_equatorial(jd: float) -> tuple[float, float]:
    """Apparent (right ascension, declination) of the Sun in degrees (Meeus ch. 25)."""
    t = (jd - 2451545.0) / 36525.0
    l0 = 280.46646 + 36000.76983 * t + 0.0003032 * t * t
    m = math.radians(357.52911 + 35999.05029 * t - 0.0001537 * t * t)
    c = ((1.914602 - 0.004817 * t - 0.000014 * t * t) * math.sin(m)
         + (0.019993 - 0.000101 * t) * math.sin(2 * m) + 0.000289 * math.sin(3 * m))
    omega = math.radians(125.04 - 1934.136 * t)
    lam = math.radians(l0 + c - 0.00569 - 0.00478 * math.sin(omega))
    eps0 = 23.0 + (26.0 + (21.448 - t * (46.8150 + t * (0.00059 - 0.001813 * t))) / 60.0) / 60.0
    eps = math.radians(eps0 + 0.00256 * math.cos(omega))
    ra = math.degrees(math.atan2(math.cos(eps) * math.sin(lam), math.cos(lam))) % 360.0
    return ra, math.degrees(math.asin(math.sin(eps) * math.sin(lam)))


def sidereal_time_deg(jd: float) -> float:
    """Greenwich mean sidereal time in degrees (Meeus eq. 12.4)."""
    t = (jd - 2451545.0) / 36525.0
    return (280.46061837 + 360.98564736629 * (jd - 2451545.0) + 0.000387933 * t * t
            - t ** 3 / 38710000.0) % 360.0


def sun_position(when: datetime, latitude_deg: float, longitude_deg: float) -> SunPosition:
    """The sun's elevation and compass azimuth seen from (latitude, longitude east) at ``when``."""
    require(-90 <= latitude_deg <= 90, f"latitude must be -90..90 deg, got {latitude_deg}")
    require(-180 <= longitude_deg <= 360, f"longitude must be -180..360 deg (east), got {longitude_deg}")
    jd = julian_day(when)
    ra, dec = sun_equatorial(jd)
    h = math.radians(sidereal_time_deg(jd) + longitude_deg - ra)        # local hour angle
    phi, d = math.radians(latitude_deg), math.radians(dec)
    elevation = math.asin(math.sin(phi) * math.sin(d) + math.cos(phi) * math.cos(d) * math.cos(h))
    south_based = math.atan2(math.sin(h), math.cos(h) * math.sin(phi) - math.tan(d) * math.cos(phi))
    return SunPosition(math.degrees(elevation), (math.degrees(south_based) + 180.0) % 360.0, dec, ra)
