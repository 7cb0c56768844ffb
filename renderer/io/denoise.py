"""Intel Open Image Denoise through the optional ``pyoidn`` package (``pip install .[denoise]``),
guided by the albedo and normal AOVs. Our film is a box filter with independent samples per
pixel, so noise stays uncorrelated between pixels, as the denoiser expects."""
from __future__ import annotations

import numpy as np

from renderer.errors import RenderError


def denoise(color: np.ndarray, albedo: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Denoised linear HDR RGB (H, W, 3) float32."""
    try:
        import pyoidn
    except ImportError:
        raise RenderError("--denoise needs Intel Open Image Denoise: pip install '.[denoise]' (package pyoidn)") from None
    f32 = lambda a: np.ascontiguousarray(a, dtype=np.float32)
    return np.asarray(pyoidn.denoise(f32(color), f32(albedo), f32(normal), hdr=True), dtype=np.float32)
