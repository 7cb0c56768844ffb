"""pbrt's transform directives as 4x4 matrices, and the matrix helpers the builder needs.

Conventions follow pbrt: matrices map column vectors (``p' = M p``); ``LookAt`` yields
camera-from-world in pbrt's left-handed camera frame (+z forward, +y up, +x = up x forward).
"""
from __future__ import annotations

import math
import tokenize
import zipfile
from dataclasses import replace
from pathlib import Path
from typing import BinaryIO

import numpy as np

from renderer.errors import Location, SceneError
from renderer.scene.description import MeshDesc
from renderer.scene.parser import require_file


def translate(d: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = d
    return m


def scale(s: np.ndarray) -> np.ndarray:
    return np.diag([*s, 1.0])


def rotate(degrees: float, axis: np.ndarray, loc: Location) -> np.ndarray:
    """Rotation by ``degrees`` about ``axis`` (Rodrigues' formula, as pbrt's Rotate)."""
    n = np.linalg.norm(axis)
    if n == 0.0:
        raise SceneError("Rotate: the axis has zero length", loc)
    a = np.asarray(axis) / n
    t = math.radians(degrees)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    m = np.eye(4)
    m[:3, :3] = np.eye(3) + math.sin(t) * k + (1.0 - math.cos(t)) * (k @ k)
    return m


def world_from_camera(eye, target, up) -> np.ndarray:
    """The camera-to-world matrix of pbrt's ``LookAt``: +z = the view direction, +x = up x dir,
    +y = dir x (+x). Raises ValueError for a degenerate eye, target or up."""
    eye, target, up = (np.asarray(v, dtype=np.float64) for v in (eye, target, up))
    d = target - eye
    if np.linalg.norm(d) == 0.0:
        raise ValueError("the eye and the point looked at coincide")
    if np.linalg.norm(up) == 0.0:
        raise ValueError("the up vector has zero length")
    d = d / np.linalg.norm(d)
    right = np.cross(up / np.linalg.norm(up), d)
    if np.linalg.norm(right) < 1e-12:
        raise ValueError("the up vector and the viewing direction are parallel")
    right /= np.linalg.norm(right)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, np.cross(d, right), d, eye
    return m


def look_at(eye: np.ndarray, target: np.ndarray, up: np.ndarray, loc: Location) -> np.ndarray:
    """pbrt's LookAt directive, which yields camera-from-world."""
    try:
        return np.linalg.inv(world_from_camera(eye, target, up))
    except ValueError as e:
        raise SceneError(f"LookAt: {e}", loc) from None


def from_pbrt_matrix(values: list[float]) -> np.ndarray:
    """The 16 numbers of Transform/ConcatTransform: pbrt reads them row by row and transposes,
    so the last four hold the translation (each group of four is a column)."""
    return np.asarray(values, dtype=np.float64).reshape(4, 4).T


def swaps_handedness(m: np.ndarray) -> bool:
    return bool(np.linalg.det(m[:3, :3]) < 0.0)


def inverse(m: np.ndarray, what: str, loc: Location) -> np.ndarray:
    """The inverse of a transform that must be invertible where ``what`` uses it: in float64 and as
    the device holds it, in float32 (two Scale 1e-45 make a float64 matrix of determinant 1e-90
    that float32 rounds to zero, which the upload then failed to invert)."""
    if not np.all(np.isfinite(m)):
        raise SceneError(f"{what}: the current transform has infinite or NaN entries", loc)
    with np.errstate(all="ignore"):
        m32 = m.astype(np.float32).astype(np.float64)
    # beyond float32's range altogether: check_single_precision says so where it matters
    candidates = (m, m32) if np.all(np.isfinite(m32)) else (m,)
    invs = []
    for candidate in candidates:
        try:
            with np.errstate(all="ignore"):
                invs.append(np.linalg.inv(candidate))
        except np.linalg.LinAlgError:
            invs.append(None)
    if any(inv is None or not np.all(np.isfinite(inv)) for inv in invs) or \
            (len(invs) == 2 and np.abs(invs[1]).max() > np.finfo(np.float32).max):
        raise SceneError(f"{what}: the current transform is singular (a zero or vanishing Scale, or a degenerate "
                         "matrix, in the device's single precision)", loc)
    return invs[0]


def transformed_mesh(mesh: MeshDesc, m: np.ndarray) -> MeshDesc:
    """Bake an affine transform into a mesh; normals go with the inverse transpose."""
    if np.allclose(m, np.eye(4), rtol=0.0, atol=1e-12):
        return mesh
    a = m[:3, :3]
    P = (mesh.positions.astype(np.float64) @ a.T + m[:3, 3]).astype(np.float32)
    N = None
    if mesh.normals is not None:
        n = mesh.normals.astype(np.float64) @ np.linalg.inv(a)
        N = (n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)).astype(np.float32)
    return replace(mesh, positions=P, normals=N)


#: More instances than this in one transforms file (2 GiB of float64 matrices) are refused.
MAX_INSTANCES = 1 << 24


def read_instance_transforms(path: Path, loc: Location) -> np.ndarray:
    """(N, 4, 4) instance matrices from a ``.npy`` (the array itself) or ``.npz`` (its array
    ``transforms``) file: our extension for placing many instances of one object. The array's
    header is checked against the bytes that hold it before anything is allocated."""
    require_file(path, loc, "instance transforms")
    try:
        if zipfile.is_zipfile(path):
            with zipfile.ZipFile(path) as z:
                names = [n.removesuffix(".npy") for n in z.namelist()]
                if "transforms" not in names:
                    raise SceneError(f'{path}: no array named "transforms" (has {", ".join(names) or "none"})',
                                     loc)
                info = z.getinfo(z.namelist()[names.index("transforms")])
                with z.open(info) as f:
                    T = _checked_npy(f, info.file_size, path, loc)
        else:
            with open(path, "rb") as f:
                T = _checked_npy(f, path.stat().st_size, path, loc)
        T = np.asarray(T, dtype=np.float64)
    except (OSError, ValueError, EOFError, SyntaxError, tokenize.TokenError, zipfile.BadZipFile) as e:
        # numpy parses the header as Python literals: a garbled one raises SyntaxError/TokenError
        raise SceneError(f"{path}: cannot read instance transforms ({e})", loc) from e
    if not np.all(np.isfinite(T)):
        raise SceneError(f"{path}: instance transforms contain NaN or infinite values", loc)
    with np.errstate(all="ignore"):
        singular = np.flatnonzero(~(np.abs(np.linalg.det(T)) > 0.0) | ~np.isfinite(np.linalg.det(T)))
    if len(singular):
        raise SceneError(f"{path}: instance transform {singular[0]} is singular (a zero scale or a degenerate "
                         f"matrix; {len(singular)} in all)", loc)
    return T


def _checked_npy(f: BinaryIO, size: int, path: Path, loc: Location) -> np.ndarray:
    """Read one ``.npy`` stream of ``size`` bytes whose header must promise an (N, 4, 4) array of
    numbers that fits in those bytes."""
    version = np.lib.format.read_magic(f)
    read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
    shape, fortran_order, dtype = read_header(f)
    if len(shape) != 3 or shape[1:] != (4, 4):
        raise SceneError(f"{path}: instance transforms must have shape (N, 4, 4), not {shape}", loc)
    if dtype.kind not in "fiu":
        raise SceneError(f"{path}: instance transforms must be numbers, not {dtype}", loc)
    if shape[0] > MAX_INSTANCES:
        raise SceneError(f"{path}: {shape[0]} instances exceed the limit of {MAX_INSTANCES}", loc)
    needed = shape[0] * 16 * dtype.itemsize
    if needed > size - f.tell():
        raise SceneError(f"{path}: the header promises {shape[0]} matrices ({needed} bytes) but the file "
                         f"holds {max(size - f.tell(), 0)} bytes of data (truncated?)", loc)
    data = np.frombuffer(f.read(needed), dtype=dtype)
    if data.size != shape[0] * 16:
        raise SceneError(f"{path}: instance transforms are truncated", loc)
    return data.reshape(shape, order="F" if fortran_order else "C")


def check_single_precision(mesh: MeshDesc, ctm: np.ndarray, name: str, loc: Location) -> None:
    """The device works in float32: a shape placed beyond its range would silently vanish."""
    lo, hi = mesh.positions.min(axis=0), mesh.positions.max(axis=0)
    corners = np.array([[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    with np.errstate(over="ignore", invalid="ignore"):
        world = (corners @ ctm.T).astype(np.float32)
    if not np.all(np.isfinite(world)):
        raise SceneError(f'Shape "{name}": its world-space position is beyond single precision (float32) '
                         "range", loc)
