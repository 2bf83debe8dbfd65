"""Numba starts at the first call of a compiled physics function, once: importing the kernel
and packing a row leave its cache alone, and threads calling at once all get the compiled
function."""

from __future__ import annotations

import subprocess
import sys

SCRIPT = """
import numpy as np
from hems_ros.physics import kernel, kernel_sources, load_params, rows
kernel_sources.use_current_cache = lambda: print("checked")
params = load_params("table41")
p, s = rows.pack(params), rows.initial_state(params)
print("packed")
kernel.steps(p, s, 0, 10.0, 1e-3, np.zeros(rows.N_O), 1)
print("stepped")
"""


def test_the_cache_is_checked_when_the_first_compiled_function_is_called():
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["packed", "checked", "stepped"]


THREADS = """
import threading
from hems_ros.physics import kinetics
barrier, results = threading.Barrier(4), []
def first_call():
    barrier.wait()
    results.append(kinetics.effective_temperatures(50.0, 2e8, 1e-7, 2e-7))
threads = [threading.Thread(target=first_call) for _ in range(4)]
for t in threads:
    t.start()
for t in threads:
    t.join()
again = kinetics.effective_temperatures(50.0, 2e8, 1e-7, 2e-7)
print(results == [again] * 4, type(kinetics.effective_temperatures).__name__)
"""


def test_threads_that_call_first_at_once_all_get_the_compiled_function():
    done = subprocess.run(
        [sys.executable, "-c", THREADS], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "CPUDispatcher"]
