"""Terrain generators (dunes, ripples, grains): metres, +y up, wind along +x."""
