"""Images through OpenImageIO (issue 32): the formats pbrt-v4 reads (.hdr, .pfm, .tga besides EXR
and PNG), 8-bit files kept 8-bit on the device with exactly the values a float image would give,
and headers that claim more than the machine holds refused by name before anything is allocated."""
from __future__ import annotations

import zlib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from renderer.io.images import code_values, read_exr, read_image, read_stored, write_exr

SCENE = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [24] "integer yresolution" [16]
Sampler "independent" "integer pixelsamples" [2]
WorldBegin
{light}
{texture}
Material "diffuse" "texture reflectance" "t"
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-2 -2 0 2 -2 0 2 2 0 -2 2 0]
    "point2 uv" [0 0 1.5 0 1.5 1.5 0 1.5]
Material "conductor" "float roughness" 0.2
Shape "sphere" "float radius" 0.6
"""


def _write_oiio(path: Path, pixels: np.ndarray) -> None:
    """Write ``pixels`` in the format of ``path``'s extension with OpenImageIO's own writer."""
    import OpenImageIO as oiio

    h, w, c = pixels.shape
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), oiio.ImageSpec(w, h, c, "uint8" if pixels.dtype == np.uint8 else "float"))
    assert out.write_image(pixels)
    out.close()


@pytest.mark.parametrize("suffix, dtype", [(".hdr", np.float32), (".pfm", np.float32), (".tga", np.uint8)])
def test_the_formats_pbrt_reads_are_read(tmp_path, suffix, dtype):
    rng = np.random.default_rng(3)
    pixels = (rng.integers(0, 256, (6, 10, 3)).astype(np.uint8) if dtype == np.uint8
              else rng.random((6, 10, 3)).astype(np.float32) * 4)
    _write_oiio(tmp_path / f"img{suffix}", pixels)
    stored = read_stored(tmp_path / f"img{suffix}")
    assert stored.dtype == dtype and stored.shape == (6, 10, 3)
    if suffix == ".hdr":       # RGBE: 8 bits of mantissa per channel under the pixel's largest exponent
        assert np.all(np.abs(stored - pixels) <= pixels.max(axis=2, keepdims=True) / 64)
    else:                      # .pfm is float32; .tga stores the 8-bit codes themselves
        np.testing.assert_array_equal(stored, pixels)


def test_a_radiance_hdr_environment_map_renders(tmp_path):
    import renderer

    _write_oiio(tmp_path / "sky.hdr", np.full((8, 16, 3), 0.5, np.float32))
    (tmp_path / "s.pbrt").write_text(SCENE.format(light='LightSource "infinite" "string filename" "sky.hdr"',
                                                  texture='Texture "t" "spectrum" "constant" "rgb value" [0.5 0.5 0.5]'))
    img = renderer.render(renderer.load_scene(tmp_path / "s.pbrt"), spp=2, seed=1)
    assert np.all(np.isfinite(img)) and img.mean() > 0.05


def test_8bit_files_stay_8bit_and_one_channel_files_one_channel(tmp_path):
    from renderer.scene.description import TextureDesc  # noqa: F401  (the table's own inputs)
    from renderer.textures.table import TextureTable

    rng = np.random.default_rng(4)
    Image.fromarray(rng.integers(0, 256, (30, 40, 3), dtype=np.uint8)).save(tmp_path / "rgb.png")
    Image.fromarray(rng.integers(0, 256, (30, 40), dtype=np.uint8)).save(tmp_path / "grey.png")
    table = TextureTable()
    _, w, h, rgb_store = table._load_image(tmp_path / "rgb.png", "sRGB", None)
    _, _, _, grey_store = table._load_image(tmp_path / "grey.png", "linear", None)
    assert (w, h) == (40, 30) and rgb_store[0] == 3 and grey_store[0] == 1
    assert [c.dtype for c in table.codes] == [np.uint8, np.uint8]
    assert sum(c.size for c in table.codes) == 40 * 30 * 4          # three bytes and one byte a texel
    assert table.pixels == [] and table.n_pixels == 0                # no float copy of either
    write_exr(tmp_path / "height.exr", rng.random((30, 40, 1)).astype(np.float32))
    _, _, _, float_store = table._load_image(tmp_path / "height.exr", "linear", None)
    assert float_store[0] == -1 and table.n_values == 2 * 256 + 40 * 30    # one float a texel, not three
    assert table.pixels == []


def test_a_one_channel_float_map_renders_exactly_as_its_three_channel_copy(tmp_path):
    import renderer

    grey = np.random.default_rng(8).random((20, 30, 1)).astype(np.float32)
    write_exr(tmp_path / "one.exr", grey)
    write_exr(tmp_path / "three.exr", np.repeat(grey, 3, axis=2))
    light = 'LightSource "distant" "point3 from" [0 0 1] "point3 to" [0 0 0] "rgb L" [3 3 3]'
    images = []
    for name in ("one", "three"):
        tex = f'Texture "t" "spectrum" "imagemap" "string filename" "{name}.exr"'
        (tmp_path / f"{name}.pbrt").write_text(SCENE.format(light=light, texture=tex))
        images.append(renderer.render(renderer.load_scene(tmp_path / f"{name}.pbrt"), spp=2, seed=4))
    np.testing.assert_array_equal(images[0], images[1])
    assert images[0].mean() > 0.01


@pytest.mark.parametrize("texture, light", [
    ("rgb.png", 'LightSource "distant" "point3 from" [0 0 1] "point3 to" [0 0 0] "rgb L" [3 3 3]'),
    ("grey.png", 'LightSource "distant" "point3 from" [0 0 1] "point3 to" [0 0 0] "rgb L" [3 3 3]'),
    (None, 'LightSource "infinite" "string filename" "{env}"'),
    (None, 'LightSource "infinite" "string filename" "{env}" "float illuminance" 2000'),
])
def test_an_8bit_file_renders_exactly_as_its_decoded_float_image(tmp_path, texture, light):
    """The same pixels as 8-bit codes (decoded through the 256-entry table on the device) and as
    a float32 EXR of the decoded values: the two renders are equal bit for bit."""
    import renderer

    rng = np.random.default_rng(5)
    Image.fromarray(rng.integers(0, 256, (20, 30, 3), dtype=np.uint8)).save(tmp_path / "rgb.png")
    Image.fromarray(rng.integers(0, 256, (20, 30), dtype=np.uint8)).save(tmp_path / "grey.png")
    Image.fromarray(rng.integers(0, 256, (16, 32, 3), dtype=np.uint8)).save(tmp_path / "env.png")
    images = {}
    for kind in ("png", "exr"):
        for name in ("rgb", "grey", "env"):
            if kind == "exr":        # what the 8-bit file means, written as float32
                write_exr(tmp_path / f"{name}.exr", read_image(tmp_path / f"{name}.png",
                                                               srgb=name != "grey"))
        tex = (f'Texture "t" "spectrum" "imagemap" "string filename" "{texture[:-4]}.{kind}"'
               + (' "string encoding" "linear"' if texture == "grey.png" and kind == "png" else "")
               if texture else 'Texture "t" "spectrum" "constant" "rgb value" [0.5 0.5 0.5]')
        (tmp_path / f"{kind}.pbrt").write_text(SCENE.format(light=light.format(env=f"env.{kind}"), texture=tex))
        images[kind] = renderer.render(renderer.load_scene(tmp_path / f"{kind}.pbrt"), spp=2, seed=9)
    np.testing.assert_array_equal(images["png"], images["exr"])
    assert images["png"].mean() > 0.01


def test_8bit_decode_through_the_code_table_matches_the_per_pixel_formula(tmp_path):
    from renderer.color.rgb import srgb_to_linear

    codes = np.arange(256, dtype=np.uint8).reshape(16, 16)
    Image.fromarray(codes).save(tmp_path / "c.png")
    np.testing.assert_array_equal(read_stored(tmp_path / "c.png")[..., 0], codes)
    np.testing.assert_array_equal(code_values(True), srgb_to_linear(np.arange(256, dtype=np.float32) / 255.0))


def _png_claiming(width: int, height: int) -> bytes:
    """A PNG whose header claims width x height RGB pixels, followed by a token of pixel data."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return len(data).to_bytes(4, "big") + kind + data + zlib.crc32(kind + data).to_bytes(4, "big")

    ihdr = width.to_bytes(4, "big") + height.to_bytes(4, "big") + bytes([8, 2, 0, 0, 0])
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64))
            + chunk(b"IEND", b""))


@pytest.mark.parametrize("side", [20_000, None])
def test_headers_claiming_more_than_the_file_or_the_machine_are_refused_in_one_line(tmp_path, side):
    """A 69-byte PNG claiming 1.1 GB, or an image just too big for this machine's memory: refused
    naming the file, before the pixels are allocated."""
    from renderer.device.footprint import machine_memory

    side = side or int((machine_memory() / 3) ** 0.5) + 1000
    (tmp_path / "big.png").write_bytes(_png_claiming(side, side))
    with pytest.raises(OSError, match="cannot read image") as info:
        read_stored(tmp_path / "big.png")
    assert str(tmp_path / "big.png") in str(info.value) and "\n" not in str(info.value)


def test_an_exr_whose_mangled_header_gets_a_message_that_is_not_text_is_refused_by_name(tmp_path):
    """OpenImageIO's error quotes the mangled attribute name (a byte 0x80, not UTF-8) and its Python
    binding fails to decode it: still our one-line refusal naming the file (found by the fuzzer)."""
    write_exr(tmp_path / "bad.exr", np.zeros((4, 8, 3), np.float32))
    data = (tmp_path / "bad.exr").read_bytes()
    assert b"channels\x00chlist" in data and b"type\x00string" in data
    data = data.replace(b"channels\x00chlist", b"\x01hannels\x00chlist", 1)
    data = data.replace(b"type\x00string", b"type\x80string", 1)
    (tmp_path / "bad.exr").write_bytes(data)
    with pytest.raises(OSError, match="cannot read image") as info:
        read_stored(tmp_path / "bad.exr")
    assert str(tmp_path / "bad.exr") in str(info.value) and "\n" not in str(info.value)


def test_an_exr_claiming_more_than_the_machine_is_refused_by_name(tmp_path):
    from renderer.device.footprint import machine_memory

    side = int((machine_memory() / 12) ** 0.5) + 1000       # float RGB just too big for memory
    write_exr(tmp_path / "big.exr", np.zeros((4, 4, 3), np.float32))
    data = (tmp_path / "big.exr").read_bytes()
    at = data.index(b"dataWindow\x00box2i\x00") + len(b"dataWindow\x00box2i\x00") + 4
    (tmp_path / "big.exr").write_bytes(data[:at] + np.array([0, 0, side - 1, side - 1], "<i4").tobytes()
                                       + data[at + 16:])
    with pytest.raises(OSError, match=r"more than this machine's memory|header claims") as info:
        read_stored(tmp_path / "big.exr")       # ours, or OpenImageIO's check of the header against the file
    assert str(tmp_path / "big.exr") in str(info.value)


def test_decoding_holds_the_image_once_plus_a_strip(tmp_path):
    import tracemalloc

    from renderer.io.images import _STRIP_BYTES

    y, x = np.indices((4096, 4096), dtype=np.uint32)
    codes = np.stack([(x ^ y) & 255, (x * 3 + y) & 255, (x // 7 + y // 5) & 255], -1).astype(np.uint8)
    Image.fromarray(codes).save(tmp_path / "a.png", compress_level=1)
    del codes
    tracemalloc.start()
    try:
        stored = read_stored(tmp_path / "a.png")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert stored.dtype == np.uint8 and stored.nbytes > 4 * _STRIP_BYTES
    assert peak < stored.nbytes + 3 * _STRIP_BYTES, f"peak {peak / stored.nbytes:.2f}x the image"


def test_exr_colour_channels_are_picked_by_name(tmp_path):
    ones = np.ones((3, 4), np.float32)
    write_exr(tmp_path / "m.exr", {"albedo.R": 9 * ones, "B": 3 * ones, "G": 2 * ones, "R": ones})
    np.testing.assert_array_equal(read_image(tmp_path / "m.exr")[0, 0], [1, 2, 3])
    assert read_exr(tmp_path / "m.exr")[0]["albedo.R"][0, 0] == 9


def test_an_8bit_environment_map_is_held_as_its_codes(tmp_path):
    """The light's row holds the file's bytes and 256 code values, no float RGB copy."""
    import renderer
    from renderer.lights import infinite

    Image.fromarray(np.random.default_rng(10).integers(0, 256, (16, 32, 3), dtype=np.uint8)).save(tmp_path / "e.png")
    Image.fromarray(np.random.default_rng(11).integers(0, 256, (16, 16), dtype=np.uint8)).save(tmp_path / "g.png")
    for name, channels in (("e.png", 3), ("g.png", 1)):
        (tmp_path / "s.pbrt").write_text(SCENE.format(light=f'LightSource "infinite" "string filename" "{name}"',
                                                      texture='Texture "t" "spectrum" "constant" "rgb value" [1 1 1]'))
        light = renderer.load_scene(tmp_path / "s.pbrt").lights[0]
        e = infinite.entry(light, None)
        h, w = (16, 32) if channels == 3 else (16, 16)
        assert e.c_data.dtype == np.uint8 and e.c_data.size == h * w * channels and e.ints["channels"] == channels
        assert len(e.v_data) == 0
        np.testing.assert_array_equal(e.f_data[e.ints["lut"]:], code_values(True))
