"""Wave optics: Fresnel equations, thin-film interference and multilayer stacks as Warp functions
(``fresnel``, ``thin_film``, ``multilayer``), and the same functions on numpy arrays (re-exported
here from ``arrays``)."""
from renderer.optics.arrays import (multilayer_reflectance, multilayer_reflectance_transmittance, multilayer_rgb,
                                    multilayer_transmittance, thin_film_reflectance,
                                    thin_film_reflectance_transmittance, thin_film_rgb, thin_film_rgb_jittered)

__all__ = ["multilayer_reflectance", "multilayer_reflectance_transmittance", "multilayer_rgb",
           "multilayer_transmittance", "thin_film_reflectance", "thin_film_reflectance_transmittance",
           "thin_film_rgb", "thin_film_rgb_jittered"]
