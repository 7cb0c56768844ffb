"""Pools: many lights' or textures' bulk data end to end in one device array, without the extra
host copies that made a large image cost three times its size."""
from __future__ import annotations

import numpy as np
import warp as wp


def pooled(parts: list[np.ndarray], empty: np.ndarray, dtype, device: str) -> wp.array:
    """One device array of the non-empty ``parts`` end to end (``empty`` when there are none: Warp
    kernels want a real array). A single part is not copied on the host, and on the CPU the
    device array is that host memory itself (Warp's copy=False), so a 12000x12000 texture is held
    once. The caller keeps the parts alive as long as the device array."""
    parts = [p for p in parts if p.size]
    host = parts[0] if len(parts) == 1 else np.concatenate(parts) if parts else empty
    if wp.get_device(device).is_cpu:
        return wp.array(np.ascontiguousarray(host), dtype=dtype, device=device, copy=False)
    return wp.array(host, dtype=dtype, device=device)
