"""The parse + build stage: pbrt-v4 text -> SceneDescription, with every error located (no Warp)."""
from __future__ import annotations

import math
import numpy as np
import pytest

from renderer.errors import Location, MissingFileError, SceneError
from renderer.materials import diffuse
from renderer.parameters import TextureRef
from renderer.scene import load_description
from renderer.scene.builder import UNSUPPORTED, Builder
from renderer.scene.parser import SIGNATURES
from renderer.scene.texture_params import read_texture
from renderer.scene.tokenizer import tokenize
from scene_files import DATA, HEAD, error_at, load, write


# --- tokenizer -----------------------------------------------------------------------------------

def test_tokens_values_kinds_and_lines():
    text = 'Shape"sphere"[1 -2.5e1 .5 +3]# comment "not a string"\n\n  "a\\"b\\\\c\\n" true nan 4.5.6'
    toks = list(tokenize(text, "f.pbrt"))
    assert [(t.kind, t.value, t.loc.line) for t in toks] == [
        ("word", "Shape", 1), ("string", "sphere", 1), ("[", "[", 1), ("number", 1, 1), ("number", -25.0, 1),
        ("number", 0.5, 1), ("number", 3, 1), ("]", "]", 1), ("string", 'a"b\\c\n', 3), ("word", "true", 3),
        ("word", "nan", 3), ("word", "4.5.6", 3)]
    assert isinstance(toks[3].value, int) and isinstance(toks[4].value, float)
    assert toks[0].loc.file == "f.pbrt"


@pytest.mark.parametrize("text, line, match", [
    ('\n"abc', 2, "unterminated string at end of file"),
    ('"ab\nc"', 1, "may not span lines"),
    ('\n\n"a\\qb"', 3, "unknown escape"),
])
def test_tokenizer_errors_are_located(text, line, match):
    with pytest.raises(SceneError, match=match) as info:
        list(tokenize(text, "t.pbrt"))
    assert info.value.loc == Location("t.pbrt", line)


# --- parser errors, each with file:line -------------------------------------------------------------

@pytest.mark.parametrize("body, line, match", [
    ('\n\nFrobnicate 1 2', 5, 'unknown directive "Frobnicate"'),
    ('\n"sphere"', 4, "expected a directive"),
    ('Shape "sphere"\n  "flaot radius" 1', 4, 'unknown parameter type "flaot"'),
    ('Shape "sphere" "radius" 1', 3, "bad parameter declaration"),
    ('Shape "sphere" "float radius"\nShape "disk"', 3, 'parameter "radius" has no value'),
    ('Shape "sphere" "float radius"', 3, 'parameter "radius" has no value'),
    ('Shape "sphere" "float radius" [ 1\n\nShape "disk" ]', 3, 'unterminated "\\["'),
    ('Shape "sphere" "float radius" [ 1', 3, 'unterminated "\\["'),
    ('Shape "sphere" "float radius" [ [ 1 ] ]', 3, 'unexpected "\\["'),
    ('Shape "sphere" "float radius" ] 1', 3, "has no value"),
    ('Shape "sphere" "float radius" [ 1 ] ]', 3, "expected a directive"),
    ('Shape "sphere"\n "float radius" 1x', 4, 'expects numbers, found "1x"'),
    ('Shape "trianglemesh" "integer indices" [0 1 2.0] "point3 P" [0 0 0 1 0 0 0 1 0]', 3, "expects integers"),
    ('Shape "trianglemesh" "integer indices" [0 1 2] "point3 P" [0 0 0 1 0 0 0 1]', 3, "multiple of 3"),
    ('Shape "sphere" "string radius" 1', 3, "expects a quoted string"),
    ('Shape "sphere" "bool radius" "maybe"', 3, "true or false"),
    ('Translate 1 2\nShape "sphere"', 3, "Translate needs 3 numbers, got 2"),
    ('\nTranslate 1 2 zz', 4, 'Translate: bad number "zz"'),
    ('Shape sphere', 3, "expects a quoted string"),
])
def test_syntax_errors_name_file_and_line(tmp_path, body, line, match):
    error_at(tmp_path, HEAD + body, line, match)


def test_unexpected_end_of_file_is_located(tmp_path):
    error_at(tmp_path, HEAD + "Texture \"t\" \"float\"", 3, "unexpected end of file")


# --- includes ------------------------------------------------------------------------------------

def test_include_resolves_against_the_including_file_and_is_textual(tmp_path):
    write(tmp_path, 'Translate 0 0 2\nShape "sphere"\nInclude "deeper/c.pbrt"\n', "parts/b.pbrt")
    write(tmp_path, 'Shape "disk"\n', "parts/deeper/c.pbrt")
    s = load(tmp_path, HEAD + 'Include "parts/b.pbrt"\nShape "sphere"\n')
    assert [s.meshes[shape.mesh].name for shape in s.shapes] == ["sphere", "disk", "sphere"]
    assert s.shapes[1].loc == Location(str(tmp_path / "parts/deeper/c.pbrt"), 1)
    # the Translate inside the include stays in effect after it, as in pbrt
    assert s.instance_sets[2].transforms[0][2, 3] == 2.0


def test_errors_inside_an_include_name_the_included_file(tmp_path):
    write(tmp_path, '# comment\n\nShape "sphere" "float radius" -1\n', "inc/bad.pbrt")
    error_at(tmp_path, HEAD + 'Include "inc/bad.pbrt"', 3, "radius must be > 0", file="inc/bad.pbrt")


def test_missing_include_is_located_at_the_include_line(tmp_path):
    e = error_at(tmp_path, HEAD + '\nImport "nothere.pbrt"', 4, "not found", kind=MissingFileError)
    assert e.path == tmp_path / "nothere.pbrt"


def test_include_cycle_is_an_error(tmp_path):
    write(tmp_path, 'Include "scene.pbrt"\n', "loop.pbrt")
    error_at(tmp_path, HEAD + 'Include "loop.pbrt"', 1, "include cycle", file="loop.pbrt")


def test_missing_scene_file():
    with pytest.raises(MissingFileError):
        load_description("/nonexistent/scene.pbrt")


# --- transforms ----------------------------------------------------------------------------------

def test_lookat_matches_pbrt_construction(tmp_path):
    s = load(tmp_path, 'LookAt 1 2 3  1 2 10  0 1 0\nCamera "perspective" "float fov" 45\nWorldBegin\n')
    # dir = +z, right = cross(up, dir) = +x, up' = cross(dir, right) = +y; origin at the eye
    expect = np.array([[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]], float)
    np.testing.assert_allclose(s.camera.camera_to_world, expect, atol=1e-12)
    assert s.camera.fov_deg == 45.0

    # raster convention (pbrt's, and the camera kernel's): camera +x is image right, +y image up,
    # so with this LookAt a point at world +x lands in the right half of the image
    p = np.linalg.inv(s.camera.camera_to_world) @ [1 + 0.5, 2, 3 + 4, 1]
    width, height, t = 200, 100, math.tan(math.radians(45) / 2)
    px = (p[0] / p[2] / (t * width / height) + 1) / 2 * width
    py = (1 - p[1] / p[2] / t) / 2 * height
    assert px > width / 2 and py == pytest.approx(height / 2)

    # looking down -x from the origin with +z up: right = cross(z, -x) = -y, up' = cross(-x, -y) = +z
    s = load(tmp_path, 'LookAt 0 0 0  -1 0 0  0 0 1\nCamera "perspective"\nWorldBegin\n')
    np.testing.assert_allclose(s.camera.camera_to_world[:3, :3], [[0, 0, -1], [-1, 0, 0], [0, 1, 0]], atol=1e-12)


def test_transform_order_rotate_and_matrices(tmp_path):
    s = load(tmp_path, HEAD + 'Translate 1 2 3\nScale 2 2 2\nRotate 90 0 0 1\nShape "sphere"\n')
    m = s.instance_sets[0].transforms[0]
    # the last directive acts first: x -> (rotate) y -> (scale) 2y -> (translate) (1, 4, 3)
    np.testing.assert_allclose(m @ [1, 0, 0, 1], [1, 4, 3, 1], atol=1e-12)

    a = load(tmp_path, HEAD + 'Transform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\nShape "sphere"\n')
    np.testing.assert_allclose(a.instance_sets[0].transforms[0][:3, 3], [5, 6, 7])
    b = load(tmp_path, HEAD + 'Translate 9 9 9\nIdentity\nConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\n'
                              'Shape "sphere"\n')
    np.testing.assert_array_equal(a.instance_sets[0].transforms, b.instance_sets[0].transforms)
    c = load(tmp_path, HEAD + 'Translate 1 0 0\nConcatTransform [0 1 0 0  -1 0 0 0  0 0 1 0  0 0 0 1]\n'
                              'Shape "sphere"\n')
    # the matrix's first four numbers are its first column: x -> y, then translate
    np.testing.assert_allclose(c.instance_sets[0].transforms[0] @ [1, 0, 0, 1], [1, 1, 0, 1], atol=1e-12)


def test_motion_blur_keeps_the_shutter_open_transform(tmp_path):
    s = load(tmp_path, HEAD + 'TransformTimes 0 1\nActiveTransform EndTime\nTranslate 5 0 0\n'
                              'ActiveTransform All\nTranslate 0 1 0\nShape "sphere"\n')
    np.testing.assert_allclose(s.instance_sets[0].transforms[0][:3, 3], [0, 1, 0])
    assert [w.split(": ")[1] for w in s.warnings] == ["TransformTimes", "ActiveTransform", "ActiveTransform",
                                                      "scene has no lights"]
    error_at(tmp_path, HEAD + "ActiveTransform Sometimes", 3, "StartTime, EndTime or All")


def test_coordinate_systems_and_camera_space(tmp_path):
    s = load(tmp_path, 'LookAt 0 0 -4  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\nTranslate 5 0 0\n'
                       'CoordinateSystem "here"\nIdentity\nAttributeBegin\nCoordSysTransform "camera"\n'
                       'Shape "sphere"\nAttributeEnd\nCoordSysTransform "here"\nShape "disk"\n'
                       'CoordSysTransform "nowhere"\n')
    np.testing.assert_allclose(s.instance_sets[0].transforms[0], s.camera.camera_to_world)
    np.testing.assert_allclose(s.instance_sets[1].transforms[0][:3, 3], [5, 0, 0])
    assert any(w.endswith('no coordinate system named "nowhere"; ignored (as pbrt does)') for w in s.warnings)


# --- graphics state --------------------------------------------------------------------------------

def test_attribute_blocks_restore_state(tmp_path):
    s = load(tmp_path, HEAD + 'Material "conductor"\n'
                              'AttributeBegin\n  Translate 0 1 0\n  Material "dielectric"\n  ReverseOrientation\n'
                              '  AreaLightSource "diffuse" "blackbody L" 3000 "bool twosided" true\n'
                              '  Shape "sphere"\nAttributeEnd\nShape "sphere"\n'
                              'TransformBegin\n  Translate 7 0 0\n  Material "diffuse"\nTransformEnd\nShape "disk"\n')
    inside, after, last = s.shapes
    assert s.materials[inside.material].kind == "dielectric" and s.materials[after.material].kind == "conductor"
    assert inside.reverse_orientation and not after.reverse_orientation
    assert inside.area_light.values["twosided"] and after.area_light is None
    np.testing.assert_allclose(s.instance_sets[1].transforms[0], np.eye(4))
    # TransformBegin/End restores only the transform
    np.testing.assert_allclose(s.instance_sets[2].transforms[0], np.eye(4))
    assert s.materials[last.material].kind == "diffuse"


@pytest.mark.parametrize("body, line, match", [
    ("AttributeEnd", 3, "AttributeEnd without a matching AttributeBegin"),
    ("TransformBegin\nAttributeEnd", 4, "closes the TransformBegin at .*:3"),
    ('\nAttributeBegin\nShape "sphere"', 4, "AttributeBegin is never closed"),
    ('ObjectBegin "a"\nAttributeEnd', 4, "closes the ObjectBegin"),
    ("ObjectEnd", 3, "ObjectEnd without a matching ObjectBegin"),
])
def test_mismatched_blocks_are_located(tmp_path, body, line, match):
    error_at(tmp_path, HEAD + body, line, match)


def test_mirroring_transform_flips_orientation_as_pbrt(tmp_path):
    s = load(tmp_path, HEAD + 'Scale -1 1 1\nShape "sphere"\nReverseOrientation\nShape "sphere"\n')
    assert [sh.reverse_orientation for sh in s.shapes] == [True, False]


def test_options_and_world_order(tmp_path):
    error_at(tmp_path, 'Shape "sphere"\nWorldBegin\n', 1, "must come after WorldBegin")
    error_at(tmp_path, 'WorldBegin\n\nFilm "rgb"\n', 3, "must come before WorldBegin")
    error_at(tmp_path, 'WorldBegin\nWorldBegin\n', 2, "twice")
    path = write(tmp_path, 'Camera "perspective"\n')
    with pytest.raises(SceneError, match="no WorldBegin"):
        load_description(path)


def test_defaults_without_options(tmp_path):
    s = load(tmp_path, 'WorldBegin\nShape "sphere"\n')
    np.testing.assert_array_equal(s.camera.camera_to_world, np.eye(4))
    assert (s.camera.fov_deg, s.camera.lens_radius, s.camera.focal_distance) == (90.0, 0.0, 1e6)
    assert (s.film.width, s.film.height, s.film.filename) == (1280, 720, "pbrt.exr")
    assert (s.sampler.kind, s.sampler.spp, s.sampler.seed) == ("zsobol", 16, 0)     # pbrt-v4's default
    assert (s.integrator.kind, s.integrator.max_depth) == ("volpath", 5)     # pbrt-v4's default
    # the default material appears once, lazily: diffuse, reflectance 0.5
    assert len(s.materials) == 1 and s.materials[0].kind == "diffuse"
    assert s.materials[0].values == {} and diffuse.PARAMS.value({}, "reflectance") == 0.5
    assert s.warnings == [f'{tmp_path / "scene.pbrt"}: scene has no lights: the image will be black']


@pytest.mark.parametrize("text, line, match", [
    ('Camera "perspective" "float fov" 180\nWorldBegin', 1, "fov"),
    ('\nCamera "realistic"\nWorldBegin', 2, 'Camera "realistic" is not supported'),
    ('Camera "pinhole"\nWorldBegin', 1, 'unknown Camera "pinhole"'),
    ('Scale 0 1 1\nCamera "perspective"\nWorldBegin', 2, "singular"),
    ('LookAt 0 0 0  0 1 0  0 1 0\nWorldBegin', 1, "parallel"),
    (HEAD + 'Shape "curve" "point3 P" [0 0 0 1 1 1 2 2 2 3 3 3]', 3, 'Shape "curve" is not supported'),
    (HEAD + 'LightSource "sunsky"', 3, 'LightSource "sunsky" is not supported'),
    (HEAD + 'LightSource "goniometric"', 3, 'LightSource "goniometric" needs a "filename"'),
    (HEAD + 'Material "measured"', 3, 'Material "measured" is not supported'),
    (HEAD + 'MediumInterface "fog" ""\nShape "sphere"', 3, 'no medium named "fog"'),
    (HEAD + 'AreaLightSource "spot"', 3, 'AreaLightSource "spot" is not supported'),
    (HEAD + 'NamedMaterial "nope"\nShape "sphere"', 4, 'no material named "nope"'),
    (HEAD + 'MakeNamedMaterial "m" "string type" "diffuse"\nMakeNamedMaterial "m" "string type" "diffuse"', 4,
     "defined twice"),
    (HEAD + 'MakeNamedMaterial "m" "float roughness" 0', 3, '"string type" is required'),
    (HEAD + 'Texture "t" "colour" "constant"', 3, 'must be "float" or "spectrum"'),
    (HEAD + 'Texture "t" "float" "constant"\nTexture "t" "float" "constant"', 4, "defined twice"),
    (HEAD + 'Rotate 10 0 0 0', 3, "zero length"),
    (HEAD + 'Texture "t" "float" "bogus"', 3, 'unknown texture class "bogus"'),
    (HEAD + 'Texture "t" "float" "ptex"', 3, 'class "ptex" is not supported'),
    (HEAD + 'Texture "t" "spectrum" "wrinkled"', 3, 'has "wrinkled" as a float texture only'),
    (HEAD + 'Texture "t" "float" "marble"', 3, 'has "marble" as a spectrum texture only'),
    (HEAD + 'Texture "t" "spectrum" "imagemap" "string filename" "nope.png"', 3, "texture image not found"),
    (HEAD + 'Texture "t" "spectrum" "imagemap"', 3, 'needs "string filename"'),
    (HEAD + 'Texture "t" "float" "checkerboard" "integer dimension" 4', 3, '"dimension" must be 2 or 3'),
    (HEAD + 'Texture "t" "float" "checkerboard"\n  "string mapping" "bogus"', 4, 'unknown mapping "bogus"'),
    (HEAD + 'Texture "t" "float" "checkerboard" "rgb tex1" [1 0 0]', 3, '"tex1" must be of type float'),
    (HEAD + 'Texture "t" "float" "scale" "texture tex" "nope"', 3, 'no texture named "nope"'),
])
def test_semantic_errors_are_located(tmp_path, text, line, match):
    error_at(tmp_path, text, line, match)


def test_unsupported_things_and_unused_parameters_warn_with_location(tmp_path):
    s = load(tmp_path, 'Film "gbuffer" "integer xresolution" 32 "float bogus" 100\n'
                       'Sampler "stratified" "integer xsamples" 2 "integer ysamples" 3\n'
                       'Integrator "bdpt" "integer maxdepth" 3\nPixelFilter "gaussian"\nColorSpace "aces2065-1"\n'
                       'MakeNamedMedium "fog" "string type" "homogeneous"\nMediumInterface "" ""\n'
                       'WorldBegin\nShape "sphere" "float radius" 2 "float emission" 0.5\n'
                       'Attribute "shape" "float radius" 3\n')
    f = tmp_path / "scene.pbrt"
    assert s.warnings == [
        f'{f}:1: Film "gbuffer": rendered as an "rgb" film',
        f'{f}:1: Film "gbuffer": parameter "float bogus" is not supported and was ignored',
        f'{f}:3: Integrator "bdpt": ' + UNSUPPORTED[('Integrator', '*')][1],
        f"{f}:5: ColorSpace: colours are always linear sRGB",
        f'{f}:9: Shape "sphere": parameter "float emission" is not supported and was ignored',
        f"{f}:10: Attribute: default parameters set by Attribute are ignored",
        f"{f}: scene has no lights: the image will be black",
    ]
    assert (s.film.width, s.sampler.spp, s.sampler.kind, s.integrator.max_depth) == (32, 6, "stratified", 3)


def test_unsupported_table_is_well_formed_and_every_directive_is_handled():
    assert all(action in ("warn", "error") and reason for action, reason in UNSUPPORTED.values())
    for name in set(SIGNATURES) - {"Include", "Import"}:       # those two the parser expands
        assert hasattr(Builder, name) or (name, "*") in UNSUPPORTED, name


# --- materials and textures ------------------------------------------------------------------------

def test_named_materials_and_textures(tmp_path):
    (tmp_path / "h.png").touch()                 # loading checks the image exists; upload reads it
    s = load(tmp_path, HEAD + 'Texture "bumps" "float" "imagemap" "string filename" "h.png"\n'
                              'MakeNamedMaterial "gold" "string type" "conductor" "texture displacement" "bumps"\n'
                              'Material "diffuse"\nShape "sphere"\nNamedMaterial "gold"\nShape "disk"\n'
                              'Material "diffuse"\nShape "disk"\n')
    tex = s.textures["bumps"]
    assert (tex.value_type, tex.kind, tex.base_dir) == ("float", "imagemap", tmp_path)
    assert tex.params.string("filename") == "h.png"
    gold = s.materials[s.shapes[1].material]
    assert (gold.kind, gold.name) == ("conductor", "gold")
    assert gold.values == {"displacement": TextureRef("bumps")}     # plain values, read at load time
    assert [s.materials[sh.material].kind for sh in s.shapes] == ["diffuse", "conductor", "diffuse"]
    assert not [w for w in s.warnings if "parameter" in w]


def test_texture_parameters_are_read_and_checked_at_load_time(tmp_path):
    s = load(tmp_path, HEAD + 'Texture "c" "spectrum" "checkerboard" "rgb tex1" [1 0 0] "float uscale" 4 '
                              '"float bumpiness" 2\n'
                              'Texture "s" "spectrum" "scale" "texture tex" "c" "float scale" 0.5\n')
    assert s.warnings[0] == (f'{tmp_path / "scene.pbrt"}:3: Texture "c": parameter "float bumpiness" is not '
                             'supported and was ignored')
    checks, scaled = read_texture(s.textures["c"]), read_texture(s.textures["s"])
    np.testing.assert_array_equal(checks.value, [1.0, 0.0, 0.0])
    assert checks.uvmap == (4.0, 1.0, 0.0, 0.0)
    assert scaled.base == "c" and np.all(scaled.value == 0.5)


# --- a whole scene ------------------------------------------------------------------------------------

def test_mini_scene_round_trip():
    s = load_description(DATA / "mini.pbrt")
    assert s.path == DATA / "mini.pbrt"
    assert (s.film.width, s.film.height, s.film.filename) == (64, 48, "mini.exr")
    assert (s.sampler.kind, s.sampler.spp) == ("zsobol", 8)
    assert (s.integrator.kind, s.integrator.max_depth) == ("volpath", 7)
    np.testing.assert_allclose(s.camera.camera_to_world[:3, 3], [0, 1, -5])
    np.testing.assert_allclose(s.camera.camera_to_world[:3, 2], np.array([0, -1, 5]) / math.sqrt(26))
    assert s.camera.fov_deg == 40
    assert [m.kind for m in s.materials] == ["dielectric", "diffuse", "diffuse"]
    assert s.materials[1].values["reflectance"] == TextureRef("checks") and "checks" in s.textures
    assert [light.kind for light in s.lights] == ["infinite", "distant"]
    sun = s.lights[1].values
    assert (sun["from"], sun["scale"], sun["angularradius"]) == ((0, 10, 0), 2.0, 0.27)
    np.testing.assert_allclose(np.asarray(sun["L"]) @ [0.2126, 0.7152, 0.0722], 1.0, rtol=1e-3)   # blackbody
    emissive = [sh for sh in s.shapes if sh.area_light is not None]
    assert len(emissive) == 1 and emissive[0].area_light.values["L"] == (4, 4, 4)
    assert emissive[0].area_light.values["scale"] == 0.5
    pebble = [i for i in s.instance_sets if len(i.shapes) == 1 and s.shapes[i.shapes[0]].material == 0]
    assert len(pebble) == 2 and pebble[0].shapes == pebble[1].shapes
    for inst in s.instance_sets:
        assert inst.transforms.shape[1:] == (4, 4)
        for i in inst.shapes:
            sh = s.shapes[i]
            mesh = s.meshes[sh.mesh]
            assert 0 <= sh.material < len(s.materials)
            assert mesh.positions.dtype == np.float32 and mesh.indices.dtype == np.int32
            assert mesh.indices.max() < len(mesh.positions)
    assert s.warnings == []
