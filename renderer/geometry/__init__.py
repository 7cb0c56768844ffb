"""Geometry on the device: instanced meshes and their BVHs, ray queries, spawn offsets, and numpy ray casting."""
