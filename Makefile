# The README's two commands. Both work on a fresh machine: they create .venv and install first.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
export WARP_CACHE_PATH ?= $(CURDIR)/.warp-cache
SCENE ?= scenes/demo.pbrt
OUT ?= out/demo.png
SPP ?=

.PHONY: render test install bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/pip install --upgrade pip >/dev/null
	$(BIN)/pip install -e '.[test,denoise]'
	touch $@

install: $(VENV)/.installed

render: install
	@mkdir -p $(dir $(OUT))
	$(BIN)/render $(SCENE) -o $(OUT) $(if $(SPP),--spp $(SPP))

test: install
	$(BIN)/python -m pytest -q

bench: install
	$(BIN)/pip install -e '.[bench]' >/dev/null
	$(BIN)/python benchmarks/throughput.py

clean:
	rm -rf $(VENV) .warp-cache out
