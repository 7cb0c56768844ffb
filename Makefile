# The README's two commands. Both work on a fresh machine: they create .venv and install first.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
export WARP_CACHE_PATH ?= $(CURDIR)/.warp-cache
SCENE ?= scenes/beach.pbrt
# the beach renders as a CPU preview by default; the full frame is `assets-gen recipe
# scenes/beach.pbrt` (the final level) then `render scenes/beach.pbrt -o beach.exr --spp 4096 --device cuda`
ifeq ($(SCENE),scenes/beach.pbrt)
RES ?= 540x960
SPP ?= 16
FLAGS ?= --denoise
# the recipe's preview detail level (docs/assets.md, "Detail levels of the beach"); LEVEL=final
# or LEVEL= builds the assets as written, which the full frame needs
LEVEL ?= preview
endif
OUT ?= out/$(notdir $(SCENE:.pbrt=.png))
SPP ?=
RES ?=
FLAGS ?=
LEVEL ?=

.PHONY: render test fuzz install bench clean props demo figures gpu-check

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/pip install --upgrade pip >/dev/null
	$(BIN)/pip install -e '.[test,denoise,cluster,tev]'
	touch $@

install: $(VENV)/.installed

# builds <scene>.recipe.json first when the scene has one (only out-of-date assets are made; the
# assets folder holds one level at a time, so a level change rebuilds the entries it changes)
render: install
	@mkdir -p $(dir $(OUT))
	$(BIN)/assets-gen recipe $(SCENE) $(if $(LEVEL),--level $(LEVEL)) >/dev/null
	$(BIN)/render $(SCENE) -o $(OUT) $(if $(SPP),--spp $(SPP)) $(if $(RES),--res $(RES)) $(FLAGS)

# the props contact sheet (docs/images/props.png is this: 800x220, 64 spp, denoised)
props:
	$(MAKE) render SCENE=scenes/props.pbrt OUT=out/props.png RES=800x220 SPP=64 FLAGS=--denoise

# the core renderer's demo scene (glass, metals, area light, soft sun, depth of field)
demo:
	$(MAKE) render SCENE=scenes/demo.pbrt

# the seed report's figures 2, 3 and 8 with our generated shell and maps
figures:
	$(MAKE) render SCENE=scenes/fig2_shell.pbrt OUT=out/fig2_shell.png
	$(MAKE) render SCENE=scenes/fig3_heightmaps.pbrt OUT=out/fig3_heightmaps.png
	$(MAKE) render SCENE=scenes/fig8_bump.pbrt OUT=out/fig8_bump.png

# on one pytest-xdist worker per CPU (JOBS=0: in this process); tests/conftest.py groups them by file
JOBS ?= auto
test: install
	$(BIN)/python -m pytest -q -n $(JOBS) --dist loadgroup

# the hostile-input fuzzer at length (make test runs 60 seeded cases per kind); FUZZ_SEED picks another sequence
fuzz: install
	FUZZ_EXAMPLES=$(or $(FUZZ_EXAMPLES),5000) FUZZ_RENDER=1 $(BIN)/python -m pytest -q tests/fuzz

# on a machine with an NVIDIA GPU: the tests that render, every scene on CPU and GPU, Mitsuba's
# cuda_ad_rgb side by side and the beach's final frame, in out/gpu-check/report.md (no GPU: exits 2)
gpu-check: install
	$(BIN)/pip install -e '.[bench]' >/dev/null
	$(BIN)/python benchmarks/gpu_check.py

bench: install
	$(BIN)/pip install -e '.[bench]' >/dev/null
	$(BIN)/python benchmarks/throughput.py

clean:
	rm -rf $(VENV) .warp-cache out
