"""Wave optics: Fresnel equations and thin-film interference as Warp functions (``fresnel``,
``thin_film``), and the same functions on numpy arrays (re-exported here from ``arrays``)."""
from renderer.optics.arrays import (thin_film_reflectance, thin_film_reflectance_transmittance, thin_film_rgb,
                                    thin_film_rgb_jittered)

__all__ = ["thin_film_reflectance", "thin_film_reflectance_transmittance", "thin_film_rgb", "thin_film_rgb_jittered"]
