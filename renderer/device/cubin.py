"""What a compiled CUDA kernel will cost on the GPU, read from its cubin with NVIDIA's own tools.

``cuobjdump --dump-resource-usage`` gives each kernel's registers, stack frame (the per-thread
local memory that spills, local arrays and by-value copies live in; DRAM traffic on a GPU),
shared memory and parameter bytes; ``cuobjdump -elf`` the size of its machine code; and, where
``nvdisasm`` is installed beside it, the SASS's local loads and stores (``LDL``/``STL``), which
is how spills show. Both tools come from PyPI (``nvidia-cuda-cuobjdump``, ``nvidia-cuda-nvdisasm``,
the ``cuda`` extra); no GPU or driver is needed to read a cubin."""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from renderer.errors import RenderError

_RESOURCE = re.compile(r"Function (\S+):\s*\n\s*REG:(\d+) STACK:(\d+) SHARED:(\d+) LOCAL:(\d+)(.*)")
_PARAM = re.compile(r"CONSTANT\[0\]:(\d+)")
_TEXT = re.compile(r"^\s*\w+\s+\w+\s+([0-9a-f]+)\s.*PROGBITS.*\s\.text\.(\S+)$", re.M)
_LOCAL_ACCESS = re.compile(r"\b(LDL|STL)(\.\S+)?\b")


@dataclass(frozen=True)
class KernelResources:
    """One kernel's footprint per thread on the GPU, as the cubin states it."""

    name: str
    registers: int
    stack_bytes: int         # the local stack frame: spills, local arrays, by-value copies
    shared_bytes: int        # per block
    local_bytes: int         # local memory outside the frame
    param_bytes: int         # kernel parameters (constant bank 0)
    code_bytes: int          # the kernel's machine code (its .text section)
    local_loads: int = -1    # LDL instructions in its SASS (-1: nvdisasm not installed)
    local_stores: int = -1   # STL instructions


def tool(name: str) -> str | None:
    """The path of an NVIDIA binary tool: on PATH, or where the ``nvidia-cuda-*`` wheels put it."""
    found = shutil.which(name)
    if found:
        return found
    for root in map(Path, sys.path):
        for sub in ("cu13", "cu12", "cuda_cuobjdump", "cuda_nvdisasm"):
            candidate = root / "nvidia" / sub / "bin" / name
            if candidate.is_file() and os.access(candidate, os.X_OK):
                return str(candidate)
    return None


def _run(args: list[str], env: dict[str, str] | None = None) -> str:
    done = subprocess.run(args, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        raise RenderError(f"{Path(args[0]).name} failed on {args[-1]}: {done.stderr.strip()}")
    return done.stdout


def read_resources(cubin: str | Path) -> list[KernelResources]:
    """Every kernel entry point of ``cubin`` with its resources."""
    cuobjdump = tool("cuobjdump")
    if cuobjdump is None:
        raise RenderError("cuobjdump not found: pip install nvidia-cuda-cuobjdump (or '.[cuda]')")
    usage = _run([cuobjdump, "--dump-resource-usage", str(cubin)])
    code = {name: int(size, 16) for size, name in _TEXT.findall(_run([cuobjdump, "-elf", str(cubin)]))}
    local = _local_accesses(cuobjdump, cubin)
    out = []
    for name, reg, stack, shared, loc, rest in _RESOURCE.findall(usage):
        if not name.endswith("_kernel_forward") and not name.endswith("_kernel_backward"):
            continue
        param = _PARAM.search(rest)
        loads, stores = local.get(name, (-1, -1))
        out.append(KernelResources(name, int(reg), int(stack), int(shared), int(loc),
                                   int(param.group(1)) if param else 0, code.get(name, 0), loads, stores))
    return out


def _local_accesses(cuobjdump: str, cubin: str | Path) -> dict[str, tuple[int, int]]:
    """Per function, its LDL and STL instruction counts from the SASS (empty without nvdisasm)."""
    nvdisasm = tool("nvdisasm")
    if nvdisasm is None:
        return {}
    env = dict(os.environ, PATH=f"{Path(nvdisasm).parent}{os.pathsep}{os.environ.get('PATH', '')}")
    counts: dict[str, tuple[int, int]] = {}
    current = None
    for line in _run([cuobjdump, "-sass", str(cubin)], env).splitlines():
        head = re.match(r"\s*Function : (\S+)", line)
        if head:
            current = head.group(1)
            counts[current] = (0, 0)
            continue
        if current is None:
            continue
        for op, _width in _LOCAL_ACCESS.findall(line):
            loads, stores = counts[current]
            counts[current] = (loads + (op == "LDL"), stores + (op == "STL"))
    return counts
