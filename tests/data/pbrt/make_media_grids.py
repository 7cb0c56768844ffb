"""Write media_grids.pbrt (a uniformgrid and an emissive rgbgrid side by side, each in an
interface box) and media_fire.pbrt (a uniformgrid glowing by its temperature grid), with grid
values drawn from a fixed seed (so the files are made again byte for byte).

    python tests/data/pbrt/make_media_grids.py
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
BOX = ('Shape "trianglemesh" "point3 P" [0 0 0  1 0 0  1 1 0  0 1 0  0 0 1  1 0 1  1 1 1  0 1 1]\n'
       '  "integer indices" [0 2 1 0 3 2  4 5 6 4 6 7  0 1 5 0 5 4  3 7 6 3 6 2  0 4 7 0 7 3  1 2 6 1 6 5]\n')


def values(a: np.ndarray) -> str:
    return " ".join(f"{v:.4g}" for v in a.ravel())


def main() -> None:
    rng = np.random.default_rng(30)
    nx, ny, nz = 6, 5, 4
    x, y, z = np.meshgrid((np.arange(nx) + 0.5) / nx, (np.arange(ny) + 0.5) / ny, (np.arange(nz) + 0.5) / nz,
                          indexing="ij")
    blob = np.exp(-((x - 0.5) ** 2 + (y - 0.45) ** 2 + (z - 0.5) ** 2) / 0.08)
    density = (4 * blob * (0.6 + 0.4 * rng.random(blob.shape))).transpose(2, 1, 0)     # [z, y, x]: x fastest
    # mildly coloured: pbrt-v4 multiplies spectra where we multiply RGB, which differs for saturated colours
    r = rng.random((nz, ny, nx))
    sa = np.stack([0.6 + 0.4 * r, 0.5 + 0.4 * r, 0.4 + 0.4 * r], -1)
    ss = np.stack([2 * blob.transpose(2, 1, 0)] * 3, -1) * np.array([1.0, 1.3, 1.6])
    le = np.zeros((nz, ny, nx, 3))
    le[1:3, 1:4, 2:4] = [0.03, 0.024, 0.018]      # rgbgrid's Le is not normalised in pbrt-v4: x 106.86
    text = f"""# reference-spp: 1024
# reference-seeds: 2
# A uniformgrid ({nx}x{ny}x{nz}, scattering, g 0.2, transformed) and an rgbgrid with emission in two interface
# boxes just above a floor under a sky; written by make_media_grids.py
LookAt 0 1.5 -4.5  0 0.5 0  0 1 0
Camera "perspective" "float fov" 32
Sampler "independent"
Integrator "volpath" "integer maxdepth" 8
PixelFilter "box"
Film "rgb" "integer xresolution" 64 "integer yresolution" 40 "string filename" "media_grids.exr"
WorldBegin
LightSource "infinite" "rgb L" [0.4 0.45 0.5]
LightSource "distant" "point3 from" [-1 3 -2] "point3 to" [0 0 0] "rgb L" [2 2 2]
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
Shape "trianglemesh" "point3 P" [-5 0 -3  5 0 -3  5 0 3  -5 0 3] "integer indices" [0 1 2 0 2 3]
AttributeBegin
Translate -1.6 0.05 0
Rotate 20 0 1 0
Scale 1.4 1.2 1
MakeNamedMedium "density" "string type" "uniformgrid" "integer nx" {nx} "integer ny" {ny} "integer nz" {nz}
  "float density" [{values(density)}]
  "rgb sigma_a" [0.3 0.4 0.6] "rgb sigma_s" [1.5 1.5 1.5] "float g" 0.2
MediumInterface "density" ""
Material "interface"
{BOX}AttributeEnd
AttributeBegin
Translate 0.3 0.05 -0.2
Rotate -15 0 1 0
Scale 1.2 1.2 1.2
MakeNamedMedium "colour" "string type" "rgbgrid" "integer nx" {nx} "integer ny" {ny} "integer nz" {nz}
  "rgb sigma_a" [{values(sa)}]
  "rgb sigma_s" [{values(ss)}]
  "rgb Le" [{values(le)}] "float Lescale" 1.5 "float scale" 1.2 "float g" -0.3
MediumInterface "colour" ""
Material "interface"
{BOX}AttributeEnd
"""
    (HERE / "media_grids.pbrt").write_text(text)
    fire(rng)


def fire(rng: np.random.Generator) -> None:
    n = 5
    c = (np.arange(n) + 0.5) / n
    x, y, z = np.meshgrid(c, c, c, indexing="ij")
    core = np.exp(-((x - 0.5) ** 2 + (y - 0.35) ** 2 + (z - 0.5) ** 2) / 0.06)
    density = (1.5 * core * (0.7 + 0.3 * rng.random(core.shape))).transpose(2, 1, 0)
    temperature = (1400 + 1000 * core * (0.8 + 0.2 * rng.random(core.shape))).transpose(2, 1, 0)
    lescale = np.full((n, n, n), 0.05)
    text = f"""# reference-spp: 1024
# reference-seeds: 2
# A {n}^3 uniformgrid glowing by its temperature grid (1400-2400 K, offset 0, scale 1.6: 2240-3840 K inside;
# Lescale 0.05) just above a grey floor (not on it: coplanar faces would make the medium ambiguous) under a dim
# sky; written by make_media_grids.py
LookAt 0 0.8 -3  0 0.45 0  0 1 0
Camera "perspective" "float fov" 35
Sampler "independent"
Integrator "volpath" "integer maxdepth" 6
PixelFilter "box"
Film "rgb" "integer xresolution" 48 "integer yresolution" 40 "string filename" "media_fire.exr"
WorldBegin
LightSource "infinite" "rgb L" [0.05 0.05 0.06]
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
Shape "trianglemesh" "point3 P" [-5 0 -3  5 0 -3  5 0 3  -5 0 3] "integer indices" [0 1 2 0 2 3]
AttributeBegin
Translate -0.5 0.05 -0.5
MakeNamedMedium "fire" "string type" "uniformgrid" "integer nx" {n} "integer ny" {n} "integer nz" {n}
  "float density" [{values(density)}]
  "float temperature" [{values(temperature)}]
  "float Lescale" [{values(lescale)}]
  "float temperaturecutoff" 0 "float temperaturescale" 1.6
  "rgb sigma_a" [1 1 1] "rgb sigma_s" [0.5 0.5 0.5]
MediumInterface "fire" ""
Material "interface"
{BOX}AttributeEnd
"""
    (HERE / "media_fire.pbrt").write_text(text)


if __name__ == "__main__":
    main()
