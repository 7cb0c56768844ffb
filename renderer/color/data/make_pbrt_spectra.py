"""Extract pbrt-v4's named spectra (measured metal eta/k, Sellmeier-sampled glass indices) from its
source into ``pbrt_spectra.json``, the table ``renderer.color.named_spectra`` reads.

The data are the measured tables pbrt-v4 (github.com/mmp/pbrt-v4, Apache-2.0) carries in
``src/pbrt/util/spectrum.cpp``, taken as pbrt ships them so a scene naming one renders with
pbrt's own numbers. Run with a pbrt-v4 checkout:

    python renderer/color/data/make_pbrt_spectra.py PATH/TO/pbrt-v4/src/pbrt/util/spectrum.cpp
"""
from __future__ import annotations

import json
import re
import sys
from pathlib import Path

#: pbrt-v4's name for each array it defines (its NamedSpectrum table).
NAMES = {
    "metal-Ag-eta": "Ag_eta", "metal-Ag-k": "Ag_k", "metal-Al-eta": "Al_eta", "metal-Al-k": "Al_k",
    "metal-Au-eta": "Au_eta", "metal-Au-k": "Au_k", "metal-Cu-eta": "Cu_eta", "metal-Cu-k": "Cu_k",
    "metal-CuZn-eta": "CuZn_eta", "metal-CuZn-k": "CuZn_k", "metal-MgO-eta": "MgO_eta", "metal-MgO-k": "MgO_k",
    "metal-TiO2-eta": "TiO2_eta", "metal-TiO2-k": "TiO2_k",
    "glass-BK7": "GlassBK7_eta", "glass-BAF10": "GlassBAF10_eta", "glass-FK51A": "GlassFK51A_eta",
    "glass-LASF9": "GlassLASF9_eta", "glass-F5": "GlassSF5_eta", "glass-F10": "GlassSF10_eta",
    "glass-F11": "GlassSF11_eta",
}


def extract(source: str) -> dict[str, list[list[float]]]:
    """{pbrt name: [[wavelength nm, value], ...]} for every entry of NAMES."""
    out = {}
    for name, array in NAMES.items():
        m = re.search(rf"const Float {array}\[\] = \{{(.*?)\}};", source, flags=re.S)
        if m is None:
            raise SystemExit(f"{array} not found")
        numbers = [float(x) for x in re.findall(r"[-+]?\d*\.?\d+(?:[eE][-+]?\d+)?", m.group(1))]
        out[name] = [numbers[i:i + 2] for i in range(0, len(numbers), 2)]
    return out


if __name__ == "__main__":
    data = {"source": "pbrt-v4 src/pbrt/util/spectrum.cpp (github.com/mmp/pbrt-v4, Apache-2.0)",
            "spectra": extract(Path(sys.argv[1]).read_text())}
    (Path(__file__).parent / "pbrt_spectra.json").write_text(json.dumps(data, indent=0) + "\n")
