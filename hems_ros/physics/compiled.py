"""The step kernel compiled ahead of time that node processes run, used only while it matches
the sources (kernel_sources.py).

A unit node (and a finger controller, whose thermal guard runs the unit's model) steps with
:func:`step_kernel`: ``kernel.steps`` compiled ahead of time by numba.pycc into the extension
module ``_kernel_aot`` beside this file, which `make setup` builds for the host CPU (``python
-m hems_ros.physics.compiled <path>``). It imports with numpy alone, where numba's JIT would
add about 120 MB to each of these processes (docs/design.md). The module returns the
sources' hash it was built with (kernel_sources.build_hash); while that differs from the
current one (the physics edited without `make setup`, or the tree moved to another CPU) or
the module is missing, step_kernel falls back to numba's JIT kernel, with a warning, and the
results stay those of the sources.
"""

from __future__ import annotations

import functools
import importlib
import sys
import warnings
from pathlib import Path
from typing import Any, Callable

from hems_ros.physics.kernel_sources import HERE, build_hash

MODULE = "_kernel_aot"
STEPS_SIGNATURE = "i8(f8[::1], f8[::1], i8, f8, f8, f8[::1], i8)"


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
    return _jit_steps()


def _jit_steps() -> Any:
    """numba's JIT dispatcher of ``kernel.steps``; numba and the kernel's modules load only
    here, so that a node with the compiled module runs without them."""
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
    dispatcher = _jit_steps()
    built_with = build_hash()
    cc = CC(MODULE)
    cc.output_dir, cc.output_file, cc.target_cpu = str(HERE), path.name, "host"
    cc.export("steps", STEPS_SIGNATURE)(dispatcher.py_func)
    cc.export("build_hash", "i8()")(lambda: built_with)
    cc.compile()


if __name__ == "__main__":
    build(Path(sys.argv[1]))
