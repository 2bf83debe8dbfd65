"""The step kernel compiled ahead of time (hems_ros.physics.compiled) gives the numba JIT
kernel's bits, and a process falls back to the JIT kernel when that module is stale or missing."""

from __future__ import annotations

import importlib
import subprocess
import sys

import numpy as np
import pytest

from hems_ros.physics import compiled, electrical, kernel, kernel_sources, load_params, rows


def _fresh_module():
    try:
        module = importlib.import_module(f"hems_ros.physics.{compiled.MODULE}")
    except ImportError:
        pytest.fail("the compiled kernel is missing: run `make setup`")
    if module.build_hash() != kernel_sources.build_hash():
        pytest.fail("the compiled kernel was built from other sources: run `make setup`")
    return module


def _profile(rng: np.random.Generator) -> list[tuple[str, float, int]]:
    """(drive, value, steps per call): heating through the transformation, a hold and random
    duty inside the band (minor loops), cooling back, then the other drives a unit takes."""
    random_duty = [
        ("duty", float(d), int(n))
        for d, n in zip(rng.uniform(0, 100, 400), rng.integers(1, 25, 400))
    ]
    return (
        [("duty", 70.0, 10)] * 200
        + [("duty", 12.0, 10)] * 100
        + random_duty
        + [("duty", 0.0, 10)] * 400
        + [("current", 1.5, 7)] * 150
        + [("current", 0.0, 10)] * 300
        + [("voltage", 8.0, 1)] * 400
        + [("voltage", 0.0, 10)] * 300
        + [("temperature", float(t), 5) for t in np.linspace(25.0, 130.0, 300)]
        + [("temperature", float(t), 5) for t in np.linspace(130.0, 25.0, 300)]
    )


@pytest.mark.parametrize("name", ["ch6_hems_index", "table41", "sheathed_calibrated"])
def test_the_compiled_steps_give_the_jit_kernels_bits(name):
    aot_steps = _fresh_module().steps
    params = load_params(name)
    packed = {False: rows.pack(params), True: rows.pack(params, temperature_drive=True)}
    states = [rows.initial_state(params), rows.initial_state(params)]
    outs = [np.zeros(rows.N_O), np.zeros(rows.N_O)]
    xi, temperature, reversals = [], [], []
    for kind, value, n in _profile(np.random.default_rng(7)):
        p = packed[kind == "temperature"]
        drive = electrical.DRIVE_NAMES[kind]
        done = [
            aot_steps(p, states[0], drive, value, 1e-3, outs[0], n),
            kernel.steps(p, states[1], drive, value, 1e-3, outs[1], n),
        ]
        assert done[0] == done[1] == n
        assert np.array_equal(states[0].view(np.int64), states[1].view(np.int64)), (kind, value)
        assert np.array_equal(outs[0].view(np.int64), outs[1].view(np.int64)), (kind, value)
        xi.append(states[0][rows.S_XI])
        temperature.append(states[0][rows.S_T])
        reversals.append(states[0][rows.S_NREV])
    # through the transformation and back, with reversals inside it (minor loops)
    assert min(xi) < 0.05 and xi[-1] > 0.95 and max(temperature) > params.kinetics.af0_c
    assert max(reversals) >= 2


FALLBACK = """
import importlib, sys, warnings
from hems_ros.physics import ActuationUnit, compiled, kernel_sources
module = importlib.import_module("hems_ros.physics." + compiled.MODULE)
assert compiled.step_kernel() is module.steps
compiled.step_kernel.cache_clear()
if sys.argv[1] == "stale":
    module.build_hash = lambda: kernel_sources.build_hash() ^ 1  # built from other sources
else:
    sys.modules["hems_ros.physics." + compiled.MODULE] = None
assert "numba" not in sys.modules
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    unit = ActuationUnit()
    ActuationUnit().advance(duty=50.0, steps=10)
unit.advance(duty=50.0, steps=10)
from hems_ros.physics import kernel
print(unit._kernel_steps is kernel.steps, len(caught))
print(caught[0].message if caught else "")
"""


@pytest.mark.parametrize("case", ["stale", "missing"])
def test_a_stale_or_missing_compiled_kernel_falls_back_to_the_jit_kernel_once(case):
    _fresh_module()
    done = subprocess.run(
        [sys.executable, "-c", FALLBACK, case], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    runs_jit_warned, message = done.stdout.splitlines()
    assert runs_jit_warned == "True 1"  # the JIT kernel, one warning for two units
    reason = "was built from other sources" if case == "stale" else "is missing"
    assert reason in message and "JIT" in message
