"""The device side of a scene: the uploaded Scene struct, the film, and the Warp runtime."""
