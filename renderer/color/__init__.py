"""Colour: sRGB conversions, blackbody, CIE spectral tables and their device weight table."""
