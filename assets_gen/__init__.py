"""Procedural assets for the summer beach scene: every generator is a pure function of
(parameters, seed) that writes files the renderer reads, with a JSON manifest beside them."""

__version__ = "0.1.0"
