"""Scalar maps in physical units for materials: a lens's film thickness (nm) and a shell's
growth-band height and ridge bump (m), in the UV squares the prop meshes write."""
