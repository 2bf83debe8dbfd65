"""The numba compilation options of every compiled function of the physics core, in one place,
and the one place numba starts for them.

``error_model="numpy"``: a division by zero gives inf or nan, which the kernel's finite-state
check reports, instead of a test per division that keeps the batch loops from vectorising.

``fastmath={"contract"}`` and nothing else: a product followed by a sum may compile to one
fused multiply-add (a single rounding instead of two). No reassociation and no finite-math
assumptions, so the results stay deterministic and nan/inf keep propagating. The scalar step
and the batch's SIMD loops fuse the same pairs (tests/physics/test_apis.py checks their bit
equality); the batch runs about 14 % faster with it (benchmarks/bench_physics.py).

Numba (with llvmlite and the scipy it imports) makes a process about 120 MB larger, and a
node process steps its unit with the kernel compiled ahead of time (compiled.py), so the
physics modules import without numba: :func:`jit`, :func:`jit_inline`, :func:`jit_parallel`
and :func:`intrinsic` only register a function. The first call of any registered function
from Python starts numba (:func:`use_numba`): it checks numba's on-disk cache against the
sources (kernel_sources.use_current_cache), then puts each function's numba dispatcher into its
module in its place, where compiled code looks it up by name (so compiled functions call one
another within a module or through their module, ``kinetics.memory_branch``, never through a
name imported from another module).
"""

from __future__ import annotations

import functools
import sys
import threading
from typing import Any, Callable, TypeVar, cast

from hems_ros.physics import kernel_sources

OPTIONS: dict[str, Any] = dict(cache=True, error_model="numpy", fastmath={"contract"})

F = TypeVar("F", bound=Callable[..., Any])

# each registered function with the njit options it adds to OPTIONS (None: a numba intrinsic)
_registered: list[tuple[Callable[..., Any], dict[str, Any] | None]] = []
_started = False
# a second thread's first call waits until every dispatcher is in place
_starting = threading.Lock()


class _Registered:
    """A registered function before numba started: a call from Python starts it, then calls
    the dispatcher that took this function's place in its module."""

    def __init__(self, func: Callable[..., Any]) -> None:
        functools.update_wrapper(self, func)
        self.py_func = func

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        use_numba()
        dispatcher = getattr(sys.modules[self.py_func.__module__], self.py_func.__name__)
        return dispatcher(*args, **kwargs)


def _compile(func: Callable[..., Any], extra: dict[str, Any] | None) -> Any:
    if extra is None:
        from numba.extending import intrinsic as numba_intrinsic

        return numba_intrinsic(func)
    from numba import njit

    return njit(**OPTIONS, **extra)(func)


def _register(func: F, extra: dict[str, Any] | None) -> F:
    with _starting:
        if _started:  # a module imported after numba started
            return cast(F, _compile(func, extra))
        _registered.append((func, extra))
        return cast(F, _Registered(func))


def jit(func: F) -> F:
    return _register(func, {})


def jit_inline(func: F) -> F:
    return _register(func, {"forceinline": True})


def jit_parallel(func: F) -> F:
    """Compiled with numba's parallel loops (``prange``)."""
    return _register(func, {"parallel": True})


def intrinsic(func: Callable[..., Any]) -> Callable[..., Any]:
    """A numba intrinsic: ``func(typingctx, *args)`` returns the signature and the code
    generator, importing what it needs from numba and llvmlite itself. Compiled code calls it
    with ``args`` alone, so its signature is not ``func``'s."""
    return _register(func, None)


# numba counts threads per calling thread, and a new thread starts with all of them, so a limit
# for the whole process (a Dask worker's one core) is kept here and applied at each call of the
# parallel batch, in whichever thread makes it (a fit's thread: diagnosis/batching.py)
_thread_limit: int | None = None


def limit_threads(threads: int | None) -> None:
    """Let the parallel functions use at most ``threads`` threads in this process (None: all
    of numba's)."""
    global _thread_limit
    _thread_limit = threads


def apply_thread_limit() -> None:
    """Apply :func:`limit_threads` in the calling thread; call it before a parallel function."""
    if _thread_limit is None:
        return
    import numba

    numba.set_num_threads(max(1, min(_thread_limit, numba.config.NUMBA_NUM_THREADS)))


def use_numba() -> None:
    """Compile the registered functions with numba from now on (once per process)."""
    global _started
    with _starting:
        if _started:
            return
        kernel_sources.use_current_cache()
        for func, extra in _registered:
            setattr(sys.modules[func.__module__], func.__name__, _compile(func, extra))
        _registered.clear()
        _started = True
