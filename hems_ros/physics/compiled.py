"""The physics kernel's compiled forms, each used only while it matches the sources: numba's
on-disk cache, and the step kernel compiled ahead of time that node processes run.

A unit node (and a finger controller, whose thermal guard runs the unit's model) steps with
:func:`step_kernel`: ``kernel.steps`` compiled ahead of time by numba.pycc into the extension
module ``_kernel_aot`` beside this file, which `make setup` builds for the host CPU (``python
-m hems_ros.physics.compiled <path>``). It imports with numpy alone, where numba's JIT would
add about 120 MB to each of these processes (docs/design.md). The module returns the
:func:`build_hash` it was built with; while that differs from the current one (the physics
edited without `make setup`, or the tree moved to another CPU) or the module is missing,
step_kernel falls back to numba's JIT kernel, with a warning, and the results stay those of
the sources.

Numba's cache tracks only each function's own file, while the kernel inlines the equation
modules and takes its layout from rows.py and its options from jit.py:
:func:`use_current_cache` drops every cached physics function when the hash changed.
"""

from __future__ import annotations

import functools
import importlib
import sys
import warnings
import zlib
from pathlib import Path
from typing import Any, Callable

HERE = Path(__file__).resolve().parent
# every file whose code or constants the compiled kernel or the batch engine holds
SOURCES = (
    "block",
    "constitutive",
    "electrical",
    "heat",
    "jit",
    "kernel",
    "kinetics",
    "loads",
    "rows",
    "sheath",
)
MODULE = "_kernel_aot"
STEPS_SIGNATURE = "i8(f8[::1], f8[::1], i8, f8, f8, f8[::1], i8)"


@functools.cache
def build_hash() -> int:
    """A checksum of the kernel's sources and of the host CPU's model and features (code
    compiled for one CPU may use instructions another lacks): CRC-32 and Adler-32 in 63 bits.
    Telling an edit from none needs no cryptographic hash, and hashlib would load OpenSSL
    (3 MB) into every unit and controller."""
    data = b"".join((HERE / f"{name}.py").read_bytes() for name in SOURCES) + _host_cpu()
    return (zlib.crc32(data) << 31) ^ zlib.adler32(data)


def _host_cpu() -> bytes:
    try:
        first = Path("/proc/cpuinfo").read_text().split("\n\n", 1)[0]
    except OSError:
        return sys.platform.encode()
    fields = ("vendor_id", "model name", "flags", "Features", "CPU implementer", "CPU part")
    return "\n".join(line for line in first.splitlines() if line.startswith(fields)).encode()


def use_current_cache() -> None:
    """Delete numba's cached compilations of the physics functions when they were cached from
    other sources (the hash they were cached with is kept beside the cache)."""
    stamp = HERE / "__pycache__" / "kernel.deps"
    current = str(build_hash())
    try:
        if stamp.is_file() and stamp.read_text() == current:
            return
        for cached in stamp.parent.glob("*.nb[ic]"):
            cached.unlink()
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(current)
    except OSError:
        pass  # read-only install: sources cannot change under it either


@functools.cache
def step_kernel() -> Callable[..., int]:
    """``kernel.steps`` compiled ahead of time, or numba's JIT kernel when the compiled module is
    missing or was built with another hash (warned once per process)."""
    try:
        module: Any = importlib.import_module(f"{__package__}.{MODULE}")
    except ImportError:
        problem = "is missing"
    else:
        if module.build_hash() == build_hash():
            return module.steps
        problem = "was built from other sources or for another CPU"
    warnings.warn(
        f"the physics kernel compiled ahead of time ({__package__}.{MODULE}) {problem}: "
        "running numba's JIT kernel instead (`make setup` builds it)",
        RuntimeWarning,
        stacklevel=2,
    )
    from hems_ros.physics import jit, kernel

    jit.use_numba()
    return kernel.steps


def build(path: Path) -> None:
    """Compile ``kernel.steps`` ahead of time for the host CPU into the extension ``path``."""
    if path.name.split(".")[0] != MODULE or path.resolve().parent != HERE:
        raise ValueError(f"{path}: the module must be {HERE / MODULE}<extension suffix>")
    try:
        from numba.pycc import CC
    except ImportError:  # pycc is pending deprecation in numba: the nodes keep the JIT kernel
        print(f"numba.pycc is gone: {path} not built, nodes run numba's JIT", file=sys.stderr)
        return
    from hems_ros.physics import jit, kernel

    jit.use_numba()
    dispatcher: Any = kernel.steps
    built_with = build_hash()
    cc = CC(MODULE)
    cc.output_dir, cc.output_file, cc.target_cpu = str(HERE), path.name, "host"
    cc.export("steps", STEPS_SIGNATURE)(dispatcher.py_func)
    cc.export("build_hash", "i8()")(lambda: built_with)
    cc.compile()


if __name__ == "__main__":
    build(Path(sys.argv[1]))
