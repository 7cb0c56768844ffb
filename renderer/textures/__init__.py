"""Textures: the device records and their evaluation (:mod:`.evaluate`), pbrt-v4's noise
(:mod:`.noise`) and the host-side table that builds them from a scene (:mod:`.table`)."""
from renderer.textures.evaluate import Textures, texture_eval
from renderer.textures.table import TextureTable

__all__ = ["TextureTable", "Textures", "texture_eval"]
