"""What every render pays before its first sample: these keep the fixed cost of a process small.

* Warp hashes a kernel before it looks for it in the kernel cache. A ``wp.static`` expression that
  reads a loop variable (``wp.static(kinds[j])`` inside ``for j in range(...)``) cannot be evaluated
  when the function is declared, and Warp then generates the whole kernel's code just to hash it,
  in every process (0.7-0.9 CPU-s for the path kernel, most of a cached render's start).
* A render of a plain scene to EXR needs neither colour-science, scipy.stats nor trimesh (0.3, 0.6
  and 1 CPU-s of imports).
"""
from __future__ import annotations

import gc
import json
import os
import subprocess
import sys
from pathlib import Path

from warp._src.codegen import Adjoint

import renderer
from renderer.device.scene import upload
from renderer.integrators.aov import aov_kernel
from renderer.integrators.path import integrator_kernel
from renderer.integrators.wavefront import wavefront_kernels

ROOT = Path(__file__).resolve().parents[2]


def test_render_kernels_hash_without_generating_code():
    """Every kernel and device function the renderer declares for a scene with several material and
    light kinds (diffuse, dielectric, conductor, textures, an area light, a sky) resolves its
    ``wp.static`` expressions when it is declared."""
    ds = upload(renderer.load_scene(ROOT / "scenes" / "demo.pbrt"), "cpu", 16, 9)
    assert len(ds.features.materials) >= 3 and len(ds.features.lights) >= 2, ds.features
    integrator_kernel(ds.features, False)      # declared (and hashed), not compiled: no launch here
    integrator_kernel(ds.features, True)
    wavefront_kernels(ds.features, False)
    wavefront_kernels(ds.features, True)
    aov_kernel(ds.features)
    # the declaration-time flag stays set on each Adjoint (the module's own is reset once it is hashed)
    deferred = [f"{a.fun_name} ({a.filename}:{a.fun_lineno})" for a in gc.get_objects()
                if isinstance(a, Adjoint) and a.has_unresolved_static_expressions
                and str(ROOT / "renderer") in str(a.filename)]
    assert not deferred, deferred


def test_a_plain_render_imports_no_colour_scipy_stats_or_trimesh(tmp_path):
    scene = tmp_path / "plain.pbrt"
    scene.write_text('LookAt 0 1 -4  0 0 0  0 1 0\nCamera "perspective" "float fov" 40\n'
                     'Sampler "zsobol" "integer pixelsamples" 4\nFilm "rgb" "integer xresolution" 16 '
                     '"integer yresolution" 12\nWorldBegin\nLightSource "infinite" "rgb L" [0.5 0.5 0.5]\n'
                     'LightSource "distant" "point3 from" [0 1 0] "rgb L" [2 2 2]\n'
                     'Material "diffuse"\nShape "sphere" "float radius" 0.7\n'
                     'Material "dielectric"\nShape "trianglemesh" "point3 P" [-4 -1 -4  4 -1 -4  4 -1 4  -4 -1 4] '
                     '"integer indices" [0 1 2 0 2 3]\n')
    code = ("import sys, json; from renderer.cli import main; rc = main(sys.argv[1:]); "
            "print(json.dumps([rc, sorted(m for m in ('colour', 'scipy.stats', 'trimesh', 'pytest') if m in sys.modules)]))")
    out = subprocess.run([sys.executable, "-c", code, str(scene), "-o", str(tmp_path / "out.exr"), "--quiet"],
                         capture_output=True, text=True, cwd=tmp_path, timeout=600,
                         env=dict(os.environ, PYTHONPATH=str(ROOT)))
    rc, imported = json.loads(out.stdout.strip().splitlines()[-1])
    assert rc == 0, out.stderr
    assert (tmp_path / "out.exr").exists()
    assert imported == [], imported
