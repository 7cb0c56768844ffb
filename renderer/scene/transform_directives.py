"""The transform directives of a pbrt scene (Translate ... ActiveTransform, named coordinate
systems), as the scene builder's base class: each post-multiplies or replaces the current
transform matrix of the graphics state, as pbrt-v4 does."""
from __future__ import annotations

from typing import TYPE_CHECKING, Callable

import numpy as np

from renderer.errors import Location, SceneError
from renderer.scene.transform import from_pbrt_matrix, look_at, rotate, scale, translate

if TYPE_CHECKING:
    from renderer.scene.parser import Directive
    from renderer.scene.state import GraphicsState


class TransformDirectives:
    """Needs the builder's ``state``, ``named_coordinate_systems``, ``warn`` and ``unsupported``."""

    state: GraphicsState
    named_coordinate_systems: dict[str, np.ndarray]
    warn: Callable[[Location, str], None]
    unsupported: Callable[[str, str, Location], None]

    def _set_ctm(self, m: np.ndarray) -> None:
        """Only the shutter-open transform is kept (motion blur is not implemented)."""
        if self.state.shutter_open_active:
            self.state.ctm = m

    def _concat(self, m: np.ndarray) -> None:
        with np.errstate(over="ignore", invalid="ignore"):     # an overflow is refused where the CTM is used
            self._set_ctm(self.state.ctm @ m)

    def Identity(self, d: Directive) -> None:
        self._set_ctm(np.eye(4))

    def Translate(self, d: Directive) -> None:
        self._concat(translate(np.asarray(d.args)))

    def Scale(self, d: Directive) -> None:
        self._concat(scale(np.asarray(d.args)))

    def Rotate(self, d: Directive) -> None:
        self._concat(rotate(float(d.args[0]), np.asarray(d.args[1:]), d.loc))

    def LookAt(self, d: Directive) -> None:
        eye, target, up = np.asarray(d.args, dtype=np.float64).reshape(3, 3)
        self._concat(look_at(eye, target, up, d.loc))

    def ConcatTransform(self, d: Directive) -> None:
        self._concat(from_pbrt_matrix(d.args))

    def Transform(self, d: Directive) -> None:
        self._set_ctm(from_pbrt_matrix(d.args))

    def CoordinateSystem(self, d: Directive) -> None:
        self.named_coordinate_systems[str(d.args[0])] = self.state.ctm

    def CoordSysTransform(self, d: Directive) -> None:
        name = str(d.args[0])
        if name not in self.named_coordinate_systems:
            self.warn(d.loc, f'CoordSysTransform: no coordinate system named "{name}"; ignored (as pbrt does)')
        else:
            self._set_ctm(self.named_coordinate_systems[name])

    def ActiveTransform(self, d: Directive) -> None:
        which = str(d.args[0])
        if which not in ("StartTime", "EndTime", "All"):
            raise SceneError(f'ActiveTransform expects StartTime, EndTime or All, not "{which}"', d.loc)
        self.unsupported(d.name, "*", d.loc)
        self.state.shutter_open_active = which != "EndTime"
