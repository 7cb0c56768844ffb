"""What of pbrt-v4 this renderer supports: the names pbrt-v4 knows, the features we ignore with a
warning or refuse, and where directives may appear. Plain tables, read by the builder."""
from __future__ import annotations

#: pbrt-v4 features this renderer does not implement. "warn": ignored with a located warning,
#: because the picture stays essentially right; "error": refused, because ignoring them would
#: change the picture badly. ``"*"`` stands for any name not listed (or for a directive without
#: a name). Parameters of supported directives that are not implemented (or misspelt) always warn.
UNSUPPORTED: dict[tuple[str, str], tuple[str, str]] = {
    ("Camera", "realistic"): ("error", "the realistic camera (lens systems) is not implemented"),
    ("Shape", "curve"): ("error", "curves are not implemented"),
    ("Material", "measured"): ("error", "measured BSDFs are not implemented"),
    ("Film", "gbuffer"): ("warn", 'rendered as an "rgb" film'),
    ("Film", "spectral"): ("warn", 'rendered as an "rgb" film'),
    ("Sampler", "pmj02bn"): ("warn", 'rendered with the "zsobol" sampler (no library we use ships the pmj02bn tables)'),
    ("Integrator", "*"): ("warn", 'rendered with the "volpath" integrator (path tracing, with media when the scene has them)'),
    ("Accelerator", "*"): ("warn", "the BVH is this renderer's own"),
    ("Attribute", "*"): ("warn", "default parameters set by Attribute are ignored"),
    ("ColorSpace", "*"): ("warn", "colours are always linear sRGB"),
    ("Option", "*"): ("warn", "options are ignored"),
    ("ActiveTransform", "*"): ("warn", "motion blur is not implemented; the shutter-open transforms are used"),
    ("TransformTimes", "*"): ("warn", "motion blur is not implemented; the shutter-open transforms are used"),
    ("WorldEnd", "*"): ("warn", "a pbrt-v3 directive; ignored"),
}

#: The names pbrt-v4 knows for each kind of object; a name outside these is an error.
KNOWN_NAMES: dict[str, frozenset[str]] = {
    "Camera": frozenset({"perspective", "orthographic", "realistic", "spherical"}),
    "Film": frozenset({"rgb", "gbuffer", "spectral"}),
    "Sampler": frozenset({"independent", "sobol", "zsobol", "halton", "pmj02bn", "paddedsobol", "stratified"}),
    "Integrator": frozenset({"path", "volpath", "ambientocclusion", "bdpt", "lightpath", "mlt", "randomwalk",
                             "simplepath", "simplevolpath", "sppm", "aov"}),
    "PixelFilter": frozenset({"box", "gaussian", "mitchell", "sinc", "triangle"}),
    "Accelerator": frozenset({"bvh", "kdtree"}),
    "Shape": frozenset({"trianglemesh", "plymesh", "sphere", "disk", "bilinearmesh", "curve", "cylinder",
                        "loopsubdiv"}),
}

#: pbrt-v3 names that pbrt-v4's --upgrade rewrites, read (with a warning) as what it writes.
PBRT_V3_NAMES = {("Film", "image"): '"rgb"', ("Camera", "environment"): '"spherical" "string mapping" "equirectangular"'}

#: As in pbrt-v4: rendering options come before WorldBegin, scene contents after it.
OPTIONS_ONLY = frozenset({"Camera", "Film", "Sampler", "Integrator", "PixelFilter", "Accelerator"})
WORLD_ONLY = frozenset({"AttributeBegin", "AttributeEnd", "Attribute", "Shape", "ReverseOrientation", "ObjectBegin",
                        "ObjectEnd", "ObjectInstance", "LightSource", "AreaLightSource", "Material",
                        "MakeNamedMaterial", "NamedMaterial", "Texture"})

#: pbrt-v4's texture classes, and the ones this renderer implements.
TEXTURE_CLASSES = frozenset({"bilerp", "checkerboard", "constant", "directionmix", "dots", "fbm", "imagemap", "marble",
                             "mix", "ptex", "scale", "windy", "wrinkled"})
SUPPORTED_TEXTURES = frozenset({"constant", "imagemap", "checkerboard", "scale", "mix", "directionmix", "bilerp",
                                "dots", "fbm", "wrinkled", "windy", "marble"})
