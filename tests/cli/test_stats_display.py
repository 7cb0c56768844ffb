"""pbrt-v4's ``--stats`` and ``--display-server``: the statistics count what the render did (camera
rays are exactly one per sample; a scene that rays all leave traces no others), and a fake tev
server, decoding tev's IPC packets itself, receives the image created once and every pass, the
last of which is the written image."""
from __future__ import annotations

import re
import socket
import struct
import threading
from pathlib import Path

import numpy as np
import pytest

from renderer.cli import EXIT_BAD_INPUT, EXIT_OK, main
from renderer.io.images import read_exr

pytest.importorskip("tevclient")

HEAD = ('Camera "perspective" "float fov" 40\nSampler "independent"\n'
        'Film "rgb" "integer xresolution" 12 "integer yresolution" 8 "string filename" "x.exr"\nWorldBegin\n'
        'LightSource "infinite" "rgb L" [0.5 0.6 0.7]\n'
        'AttributeBegin\nTranslate 0 0 -10\nShape "sphere" "float radius" 0.1\nAttributeEnd\n')  # behind the camera
PLANE = ('Material "diffuse"\nLightSource "distant" "point3 from" [0 0 -1] "point3 to" [0 0 0]\n'
         'Shape "trianglemesh" "point3 P" [-9 -9 3  9 -9 3  9 9 3  -9 9 3] "integer indices" [0 1 2 0 2 3]\n')


def scene(tmp_path: Path, body: str = "") -> Path:
    path = tmp_path / "scene.pbrt"
    path.write_text(HEAD + body)
    return path


def stat(text: str, name: str) -> str:
    m = re.search(rf"^    {re.escape(name)} +(.+)$", text, re.M)
    assert m, f"{name!r} not in\n{text}"
    return m.group(1)


def test_stats_count_camera_rays_exactly_and_nothing_else_when_every_ray_escapes(tmp_path, capsys):
    assert main([str(scene(tmp_path)), "-o", str(tmp_path / "a.exr"), "--spp", "3", "--stats", "--quiet"]) == EXIT_OK
    out = capsys.readouterr().out
    assert out.startswith("Statistics:")
    assert stat(out, "Camera rays (one per sample)") == str(3 * 12 * 8)
    assert stat(out, "Bounce, shadow and subsurface rays") == "0"
    assert (stat(out, "Passes"), stat(out, "Samples per pixel"), stat(out, "Lights")) == ("3", "3", "infinite 1")
    for phase in ("Scene parsing and building", "Kernel load", "Rendering", "Image output"):
        assert float(stat(out, phase).removesuffix(" s")) >= 0.0


def test_stats_count_the_shadow_and_bounce_rays_of_a_lit_plane(tmp_path, capsys):
    assert main([str(scene(tmp_path, PLANE)), "-o", str(tmp_path / "a.exr"), "--spp", "2", "--stats",
                 "--max-depth", "1", "--quiet"]) == EXIT_OK
    out = capsys.readouterr().out
    camera = 2 * 12 * 8
    assert stat(out, "Camera rays (one per sample)") == str(camera)
    # every camera ray hits the plane: at least one shadow ray per sample, at most a few rays more
    assert camera <= int(stat(out, "Bounce, shadow and subsurface rays")) <= 4 * camera
    assert stat(out, "Lights") == "distant 1, infinite 1"


class FakeTev:
    """A TCP server that stores every byte a client sends, and decodes tev's packets: a uint32
    length (itself included), a type byte, then the packet's fields."""

    def __init__(self):
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.data = bytearray()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        conn, _ = self.sock.accept()
        with conn:
            while chunk := conn.recv(1 << 16):
                self.data += chunk

    def packets(self) -> list[tuple[int, bytes]]:
        self.thread.join(timeout=30)
        out, i = [], 0
        while i < len(self.data):
            (n,) = struct.unpack_from("<I", self.data, i)
            out.append((self.data[i + 4], bytes(self.data[i + 5:i + n])))
            i += n
        return out


def _string(b: bytes, i: int) -> tuple[str, int]:
    j = b.index(b"\0", i)
    return b[i:j].decode(), j + 1


def decode_update(body: bytes) -> tuple[str, list[str], int, int, np.ndarray]:
    """tev's UpdateImage (type 6): grab focus, name, channels, x, y, w, h, offsets, strides, floats."""
    name, i = _string(body, 1)
    (n,) = struct.unpack_from("<i", body, i)
    i += 4
    channels = []
    for _ in range(n):
        c, i = _string(body, i)
        channels.append(c)
    x, y, w, h = struct.unpack_from("<4i", body, i)
    i += 16 + 16 * n                   # int64 offsets and strides: interleaved, checked by the reshape
    return name, channels, x, y, np.frombuffer(body[i:], dtype="<f4").reshape(h, w, n)


def test_display_server_gets_the_image_once_and_every_pass(tmp_path):
    tev = FakeTev()
    out = tmp_path / "shown.exr"
    assert main([str(scene(tmp_path, PLANE)), "-o", str(out), "--spp", "3", "--quiet",
                 "--display-server", f"127.0.0.1:{tev.port}"]) == EXIT_OK
    packets = tev.packets()
    kind, body = packets[0]
    assert kind == 4                                             # CreateImage
    name, i = _string(body, 1)
    w, h, n = struct.unpack_from("<3i", body, i)
    assert (name, w, h, n) == ("shown.exr", 12, 8, 3)
    updates = [decode_update(b) for k, b in packets[1:]]
    assert all(k == 6 for k, _ in packets[1:]) and len(updates) == 3     # one tile (12x8 < 128) per pass
    assert all(u[:4] == ("shown.exr", ["R", "G", "B"], 0, 0) for u in updates)
    ch, _ = read_exr(out)
    np.testing.assert_array_equal(updates[-1][4], np.stack([ch[c] for c in "RGB"], -1))
    assert not np.array_equal(updates[0][4], updates[-1][4])    # the passes differ: each is the current mean


@pytest.mark.parametrize("address, needle", [("nohost", "wants HOST:PORT"), ("127.0.0.1:99999", "wants HOST:PORT"),
                                             ("closed", "cannot reach tev")])
def test_display_server_errors_exit_2(tmp_path, capsys, address, needle):
    if address == "closed":
        with socket.create_server(("127.0.0.1", 0)) as s:
            address = f"127.0.0.1:{s.getsockname()[1]}"     # closed again when the render starts
    assert main([str(scene(tmp_path)), "-o", str(tmp_path / "a.exr"), "--spp", "1", "--quiet",
                 "--display-server", address]) == EXIT_BAD_INPUT
    assert needle in capsys.readouterr().err
    assert not (tmp_path / "a.exr").exists()
