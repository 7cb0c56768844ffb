"""Every generator, in the order ``assets-gen --help`` lists them: adding one is a module that
defines a :class:`~assets_gen.core.Generator` plus one line here."""
from __future__ import annotations

from assets_gen import sky, sky_lights
from assets_gen.core import Generator, GeneratorError
from assets_gen.maps import lens_thickness, shell
from assets_gen.props import palm, seashell, sunglasses, umbrella
from assets_gen.terrain import dunes, grains, imprint, near_field, placement, ripples

GENERATORS: tuple[Generator, ...] = (
    seashell.GENERATOR,
    sunglasses.GENERATOR,
    umbrella.GENERATOR,
    palm.GENERATOR,
    sky.GENERATOR,
    sky_lights.GENERATOR,
    dunes.GENERATOR,
    ripples.GENERATOR,
    grains.GENERATOR,
    near_field.GENERATOR,
    placement.GENERATOR,
    imprint.GENERATOR,
    lens_thickness.GENERATOR,
    shell.SHELL_HEIGHT,
    shell.SHELL_BUMP,
    shell.SHELL_PIGMENT,
)

BY_NAME: dict[str, Generator] = {g.name: g for g in GENERATORS}


def get(name: str) -> Generator:
    """The generator called ``name``; :class:`GeneratorError` listing the known ones otherwise."""
    if name not in BY_NAME:
        raise GeneratorError(f"unknown generator {name!r}; known: {', '.join(sorted(BY_NAME))}")
    return BY_NAME[name]
