"""Kernels that trace paths: the shared shading step, the path tracer, subsurface walks and AOVs."""
