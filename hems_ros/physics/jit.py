"""The numba compilation options of every function of the physics core, in one place.

``error_model="numpy"``: a division by zero gives inf or nan, which the kernel's finite-state
check reports, instead of a test per division that keeps the batch loops from vectorising.

``fastmath={"contract"}`` and nothing else: a product followed by a sum may compile to one
fused multiply-add (a single rounding instead of two). No reassociation and no finite-math
assumptions, so the results stay deterministic and nan/inf keep propagating. The scalar step
and the batch's SIMD loops fuse the same pairs (tests/physics/test_apis.py checks their bit
equality); the batch runs about 14 % faster with it (benchmarks/bench_physics.py).
"""

from __future__ import annotations

from numba import njit

OPTIONS = dict(cache=True, error_model="numpy", fastmath={"contract"})

jit = njit(**OPTIONS)
jit_inline = njit(**OPTIONS, forceinline=True)
