"""Sample generation: random numbers, warps to directions, distributions, frames and MIS weights."""
