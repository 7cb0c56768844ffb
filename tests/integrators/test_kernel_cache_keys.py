"""A kernel's cache key (Warp's module hash) depends on its code only, not on what else the process
compiled before: otherwise a second run of the tests, a study or a notebook recompiles kernels whose
code has not changed (23 of the suite's 70 integrator kernels did, 2026-12-03).

The cause found: Warp 1.19 hashes a function's references by scanning its source, and before the
function has been code-generated that scan resolves ``e.f`` of a local ``e`` to ``wp.e`` (2.718...),
a constant it then hashes; after code generation it knows ``e`` is local. So a local whose name is
also an attribute of the ``warp`` module or a Python builtin must not be used with an attribute."""
from __future__ import annotations

import ast
import builtins
import os
import subprocess
import sys
from pathlib import Path

import warp

ROOT = Path(__file__).resolve().parents[2]

_HASH_OF_B = """
import sys, warp as wp
wp.config.quiet = True
wp.init()
from renderer.device.scene import Features
from renderer.integrators.path import integrator_kernel
a = integrator_kernel(Features(materials=("diffuse",), bump=False, lights=("point",), escaping=()))
if sys.argv[1] == "build-a":
    a.module.load("cpu")
b = integrator_kernel(Features(materials=("coateddiffuse", "diffuse"), bump=True, lights=("distant",),
                               escaping=("infinite",)))
print(b.module.name)
"""


def _warp_functions(tree: ast.Module) -> list[ast.FunctionDef]:
    """Every function decorated with ``wp.func`` or ``wp.kernel`` (with or without arguments)."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef):
            for d in node.decorator_list:
                f = d.func if isinstance(d, ast.Call) else d
                if isinstance(f, ast.Attribute) and f.attr in ("func", "kernel") and getattr(f.value, "id", "") == "wp":
                    found.append(node)
    return found


def test_no_device_function_uses_an_attribute_of_a_local_named_like_a_warp_global():
    shadowed = set(dir(warp)) | set(dir(builtins))
    offenders = []
    for path in sorted((ROOT / "renderer").rglob("*.py")):
        for fn in _warp_functions(ast.parse(path.read_text())):
            local = {a.arg for a in ast.walk(fn.args) if isinstance(a, ast.arg)} | {
                n.id for n in ast.walk(fn) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
            roots = {n.value.id for n in ast.walk(fn) if isinstance(n, ast.Attribute) and isinstance(n.value, ast.Name)}
            offenders += [f"{path.relative_to(ROOT)}:{fn.lineno} {fn.name}: {name}" for name in sorted(local & roots & shadowed)]
    assert not offenders, offenders


def test_a_kernels_hash_does_not_depend_on_an_earlier_kernel_being_compiled(tmp_path):
    """Kernel B shares layered, diffuse and emission functions with kernel A; B's name (which holds
    its hash) is the same whether A was compiled first in the process or not."""
    env = dict(os.environ, WARP_CACHE_PATH=str(tmp_path / "cache"))
    names = [subprocess.run([sys.executable, "-c", _HASH_OF_B, how], env=env, cwd=ROOT, capture_output=True,
                            text=True, check=True).stdout.split()[-1] for how in ("build-a", "declare-only")]
    assert names[0] == names[1]
