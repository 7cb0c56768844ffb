"""Compile options shared by the render kernels (the ``module="unique"`` ones, which do not see
a source module's ``set_module_options``).

Host code is compiled with ``-menable-no-nans``: Warp's ``min``/``max`` otherwise become NaN-safe
compare chains in the hot traversal and shading code. The NaN guards keep working because
``wp.isfinite`` and the NaN tests the kernels rely on are checked by tests (a NaN sample is still
dropped and counted). CUDA code is unaffected: the flag only reaches the CPU compiler. Clang then
warns about every NaN constant in Warp's own headers (``-Wnan-infinity-disabled``); those are
Warp's identities and out-of-range returns, not our code, so that one warning is turned off. So
is ``-Wconstant-conversion``: Warp writes every integer literal as a ``const wp::int32`` before
our ``wp.uint32(...)`` cast, so a 32-bit hash constant above 2^31 (0x9E3779B9) is narrowed to the
same bits, which the cast restores. Warning flags do not change the generated code.

Warp passes every argument by value, the scene's tables too (``Scene`` is 3 kB, ``Textures``
0.7 kB, ``Lights`` 0.6 kB, ``SamplerParams`` 0.3 kB), and clang leaves the larger per-bounce
functions out of line, so each call copied its tables. Those functions (the ray queries, BSDF
loading and texture lookup, light sampling and emission, the sampler's dimensions) are declared
``@wp.func(inline=True)``: the copies go, the images stay bit-identical. Inlining everything
(``-mllvm -inline-threshold=50000``) was faster still but tripled the beach kernel's cold compile
(docs/traversal.md, "Inlining")."""
from __future__ import annotations

from typing import Any

#: ``module_options`` for the render kernels: no backward pass (nothing differentiates them; it
#: doubled the generated code), the host compiler flags above on top of Warp's default, and no
#: unrolling by Warp's code generator (``max_unroll`` 1; loops over ``wp.static`` values still
#: unroll). Warp unrolls every constant loop of up to 16 iterations in Python before the compilers
#: see it, so ``load_bsdf``'s loop over the 16 parameter slots became 16 inlined copies of the
#: texture evaluator: on sm_90 the diffuse-only path kernel took 405 s of NVRTC, 255 registers,
#: a 2,624-byte stack frame and 2.2 MB of code; without the unrolling 33 s, a 960-byte frame and
#: 0.7 MB (docs/gpu.md). Clang and NVRTC still unroll what pays; CPU images are bit-identical.
KERNEL_OPTIONS: dict[str, Any] = {"enable_backward": False, "max_unroll": 1,
                                  "cpu_compiler_flags": "-march=native -menable-no-nans -Wno-nan-infinity-disabled "
                                                        "-Wno-constant-conversion"}

#: ``launch_bounds`` that hold a CUDA kernel to 128 registers (the budget in DESIGN.md): blocks of
#: 256 threads (Warp's CUDA launches) of which at least two stay resident per SM, so ptxas fits each
#: thread in 65,536 / 512 registers instead of up to 255. What does not fit spills into the frame,
#: whose size is then the figure that decides (every kernel of the wavefront and of the AOV pass in
#: steps takes it). The CPU ignores it: its code and images are unchanged.
GPU_LAUNCH_BOUNDS = (256, 2)
