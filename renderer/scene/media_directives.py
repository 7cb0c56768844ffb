"""The participating-media directives of a pbrt scene (MakeNamedMedium, MediumInterface), as a base
class of the scene builder: media are named as they are defined, shapes and the camera record the
names current when they appear, and the names are resolved to indices at the end, because pbrt-v4
too accepts a medium defined after its first use."""
from __future__ import annotations

from typing import TYPE_CHECKING, Callable

from renderer.errors import Location, SceneError
from renderer.media.description import MediumInterfaceDesc
from renderer.scene.media_params import read_medium
from renderer.scene.transform import inverse

if TYPE_CHECKING:
    from renderer.scene.description import SceneDescription
    from renderer.scene.parser import Directive
    from renderer.scene.state import GraphicsState


class MediaDirectives:
    """Needs the builder's ``scene``, ``state``, ``warn`` and ``warn_unused``; call ``_init_media`` first."""

    scene: SceneDescription
    state: GraphicsState
    warn: Callable[[Location, str], None]
    warn_unused: Callable[[Directive], None]

    def _init_media(self) -> None:
        self.media: dict[str, int] = {}          # MakeNamedMedium names -> SceneDescription.media
        #: (shape index or -1 for the camera, inside, outside, where named): resolved at the end
        self.medium_refs: list[tuple[int, str, str, Location | None]] = []

    def MediumInterface(self, d: Directive) -> None:
        """One name: the same medium on both sides; two: inside, then outside (pbrt-v4's order)."""
        inside = str(d.args[0])
        outside = str(d.args[1]) if len(d.args) > 1 else inside
        self.state.medium_inside, self.state.medium_outside, self.state.medium_loc = inside, outside, d.loc

    def MakeNamedMedium(self, d: Directive) -> None:
        name = str(d.args[0])
        if name in self.media:
            raise SceneError(f'medium "{name}" is defined twice (first at {self.scene.media[self.media[name]].loc})',
                             d.loc)
        kind = d.params.string("type")
        if kind is None:
            raise SceneError(f'MakeNamedMedium "{name}": "string type" is required', d.loc)
        inverse(self.state.ctm, d.name, d.loc)
        self.scene.media.append(read_medium(kind, name, d.params, self.state.ctm, d.loc, self.warn))
        self.media[name] = len(self.scene.media) - 1
        self.warn_unused(d)

    def _camera_medium(self, loc: Location) -> None:
        """pbrt-v4: the camera sits in the current outside medium."""
        if self.state.medium_outside:
            self.medium_refs.append((-1, self.state.medium_outside, self.state.medium_outside, loc))

    def _shape_media(self, shape: int) -> None:
        """The current MediumInterface, for the shape just added."""
        if self.state.medium_inside or self.state.medium_outside:
            self.medium_refs.append((shape, self.state.medium_inside, self.state.medium_outside,
                                     self.state.medium_loc))

    def _copy_media(self, shapes: dict[int, int]) -> None:
        """Copies of shapes (original index -> copy's index) keep the originals' MediumInterface."""
        refs = {ref[0]: ref for ref in self.medium_refs}
        self.medium_refs.extend((copy, *refs[i][1:]) for i, copy in shapes.items() if i in refs)

    def _resolve_media(self) -> None:
        """Medium names to indices."""
        def index(name: str, loc: Location | None) -> int:
            if not name:
                return -1
            if name not in self.media:
                raise SceneError(f'no medium named "{name}" (define it with MakeNamedMedium)', loc)
            return self.media[name]

        for shape, inside, outside, loc in self.medium_refs:
            if shape < 0:
                self.scene.camera_medium = index(outside, loc)
            else:
                self.scene.shapes[shape].media = MediumInterfaceDesc(index(inside, loc), index(outside, loc))
