"""The grains' mineral mix: class fractions as asked, grains sitting on the surface given, heavy
minerals in the ripple troughs and coarse grains on the crests."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy import stats

from assets_gen.cli import main
from assets_gen.terrain.grains import ground_height
from assets_gen.terrain.sand_minerals import RipplePhase

FRACTIONS = (0.6, 0.15, 0.2, 0.05)     # heavy minerals raised so the test has 800 of them


def run(*argv: object) -> int:
    return main([str(a) for a in argv])


@pytest.fixture(scope="module")
def sorted_sand(tmp_path_factory):
    out = tmp_path_factory.mktemp("sorted")
    assert run("dunes", "--size-x", 4, "--size-z", 4, "--spacing", 0.05, "--dune-height", 0,
               "--seed", 1, "--out", out / "flat") == 0
    assert run("ripples", "--dunes", out / "flat" / "dunes_height.exr", "--coverage", 1.0,
               "--seed", 2, "--out", out / "ripples") == 0
    ripples = out / "ripples" / "ripples_displacement.exr"
    assert ripples.is_file()
    q, f, h, s = FRACTIONS
    assert run("grains", "--surface", out / "flat" / "dunes.ply", "--count", 4000, "--ripples", ripples,
               "--quartz-fraction", q, "--feldspar-fraction", f, "--heavy-fraction", h, "--shell-fraction", s,
               "--seed", 3, "--out", out / "grains") == 0
    return out


def test_class_fractions_within_sampling_error(sorted_sand):
    kind = np.load(sorted_sand / "grains" / "grains.npz")["kind"]
    counts = np.bincount(kind, minlength=4)
    assert stats.chisquare(counts, np.array(FRACTIONS) * len(kind)).pvalue > 1e-3, counts


def test_grains_sit_on_the_surface_they_are_given(sorted_sand):
    mesh = trimesh.load(sorted_sand / "flat" / "dunes.ply", process=False)
    data = np.load(sorted_sand / "grains" / "grains.npz")
    centres, r = data["transforms"][:, :3, 3].astype(np.float64), 0.5 * data["scales"].astype(np.float64)
    above = centres[:, 1] - ground_height(np.asarray(mesh.vertices), np.asarray(mesh.faces), centres[:, [0, 2]])
    # centres lie r (1 - 2 sink) above the sand, sink = 0.3 +- 0.1 of the diameter
    assert (above >= 0.2 * r - 1e-7).all() and (above <= 0.6 * r + 1e-7).all()


def test_heavy_minerals_in_troughs_coarse_grains_on_crests(sorted_sand):
    data = np.load(sorted_sand / "grains" / "grains.npz")
    kind, d = data["kind"], data["scales"].astype(np.float64)
    c = data["transforms"][:, :3, 3].astype(np.float64)
    phase = RipplePhase(sorted_sand / "ripples" / "ripples_displacement.exr")(c[:, 0], c[:, 2])
    heavy, light = phase[kind == 2], phase[kind != 2]
    assert heavy.mean() < -0.1 and heavy.mean() < light.mean() - 0.15, (heavy.mean(), light.mean())
    assert stats.mannwhitneyu(heavy, light, alternative="less").pvalue < 1e-6
    lo, hi = np.quantile(d[kind != 2], [1 / 3, 2 / 3])
    coarse, fine = light[d[kind != 2] > hi], light[d[kind != 2] < lo]
    assert coarse.mean() > fine.mean() + 0.05, (coarse.mean(), fine.mean())
    assert stats.mannwhitneyu(coarse, fine, alternative="greater").pvalue < 1e-4


def test_shell_fragments_are_flat_and_lie_flat(sorted_sand):
    shell = trimesh.load(sorted_sand / "grains" / "grain_shell.ply", process=False)
    quartz = trimesh.load(sorted_sand / "grains" / "grain_quartz.ply", process=False)
    assert np.ptp(shell.vertices[:, 1]) < 0.45 * np.ptp(quartz.vertices[:, 1])
    data = np.load(sorted_sand / "grains" / "grains.npz")
    up = data["transforms"][data["kind"] == 3][:, :3, 1] / data["scales"][data["kind"] == 3][:, None]
    assert np.allclose(up, [0, 1, 0], atol=1e-5)      # their thin axis stays vertical
