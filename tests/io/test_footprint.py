"""The memory estimate is within a factor of two of what a render really takes at its peak,
for scenes dominated by meshes, instances, textures, environment maps or the film."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from renderer.api import load_scene
from renderer.device.footprint import estimate, image_size

ROOT = Path(__file__).resolve().parents[2]
HEAD = 'Camera "perspective"\nFilm "rgb" "integer xresolution" [{w}] "integer yresolution" [{h}]\nWorldBegin\n'

#: The peak is VmHWM, this process's own high-water mark: Linux carries getrusage's ru_maxrss over
#: fork and exec, so a child of a large test process would report its parent's size.
PEAK = """import sys
from renderer.api import load_scene
from renderer.device.scene import upload
from renderer.device.film import Film
desc = load_scene(sys.argv[1]); ds = upload(desc, "cpu"); film = Film(ds.width, ds.height, "cpu")
hwm = [line for line in open("/proc/self/status") if line.startswith("VmHWM:")][0]
print(int(hwm.split()[1]) * 1024)
"""


def _peak_bytes(path: Path) -> int:
    """The peak resident memory of a process that uploads the scene: the second of two runs, so a
    cold kernel cache's compile (hundreds of MB inside clang, once per machine) is not counted."""
    for _ in range(2):
        run = subprocess.run([sys.executable, "-c", PEAK, str(path)], capture_output=True, text=True, cwd=ROOT,
                             timeout=600)
        assert run.returncode == 0, run.stderr
    return int(run.stdout.split()[-1])


@pytest.mark.parametrize("kind", ["spheres", "instances", "texture", "environment", "film"])
def test_the_estimate_is_within_a_factor_of_two_of_the_measured_peak(tmp_path, kind):
    w, h, body = 8, 8, 'LightSource "distant" "rgb L" [1 1 1]\n'
    if kind == "spheres":       # 3000 spheres of distinct radii: 3000 meshes
        body += "".join(f'Shape "sphere" "float radius" [{1 + i * 1e-3}]\n' for i in range(3000))
    elif kind == "instances":
        np.save(tmp_path / "t.npy", np.tile(np.eye(4), (400_000, 1, 1)))
        body += 'ObjectBegin "o"\nShape "sphere"\nObjectEnd\nObjectInstance "o" "string transforms" "t.npy"\n'
    elif kind == "texture":
        Image.fromarray(np.full((3000, 3000, 3), 100, np.uint8)).save(tmp_path / "t.png")
        body += ('Texture "t" "spectrum" "imagemap" "string filename" "t.png"\n'
                 'Material "diffuse" "texture reflectance" "t"\nShape "sphere"\n')
    elif kind == "environment":
        Image.fromarray(np.full((1500, 3000, 3), 100, np.uint8)).save(tmp_path / "env.png")
        body = 'LightSource "infinite" "string filename" "env.png"\nShape "sphere"\n'
    else:
        w, h, body = 4000, 3000, body + 'Shape "sphere"\n'
    path = tmp_path / "s.pbrt"
    path.write_text(HEAD.format(w=w, h=h) + body)
    guess, peak = estimate(load_scene(path), w, h), _peak_bytes(path)
    assert peak / 2 < guess < 2 * peak, f"estimate {guess / 2**20:.0f} MB, measured {peak / 2**20:.0f} MB"


def test_image_sizes_come_from_headers(tmp_path):
    from renderer.io.images import write_exr

    Image.fromarray(np.zeros((5, 7, 3), np.uint8)).save(tmp_path / "a.png")
    write_exr(tmp_path / "b.exr", np.zeros((3, 11, 3), np.float32))
    (tmp_path / "c.exr").write_bytes(b"junk")
    assert image_size(tmp_path / "a.png") == (7, 5)
    assert image_size(tmp_path / "b.exr") == (11, 3)
    assert image_size(tmp_path / "c.exr") == (0, 0)


def test_the_wavefront_path_state_is_what_its_buffers_allocate(tmp_path):
    """With the wavefront (a CUDA render's integrator), the estimate adds the path state a pass
    holds: here counted from the field types, there allocated by the integrator for one chunk of
    the whole image (one worker, as on a GPU); they agree to the few bytes that do not grow with
    the paths."""
    from renderer.device.scene import upload
    from renderer.integrators.path_state import PathBuffers
    from renderer.integrators.wavefront import Wavefront, wavefront_kernels

    w, h = 64, 48
    path = tmp_path / "s.pbrt"
    path.write_text(HEAD.format(w=w, h=h) + 'LightSource "distant" "rgb L" [1 1 1]\nShape "sphere"\n'
                    'Material "conductor"\nShape "trianglemesh" "integer indices" [0 1 2] '
                    '"point3 P" [0 0 0 1 0 0 0 1 0]\n')
    desc = load_scene(path)
    ds = upload(desc, "cpu", w, h)
    assert len(ds.features.materials) == 2
    wavefront = Wavefront(wavefront_kernels(ds.features, False), False, w * h, 1, "cpu")
    allocated = sum(getattr(b, name).capacity for b in wavefront.buffers for name in PathBuffers.vars)
    counted = estimate(desc, w, h, wavefront=True) - estimate(desc, w, h)
    assert w * h * 150 < counted <= allocated < counted + 1024, (counted, allocated)
