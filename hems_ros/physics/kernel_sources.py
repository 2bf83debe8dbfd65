"""The sources the physics kernel's compiled forms are built from, and numba's on-disk cache
kept in step with them.

Numba's cache tracks only each function's own file, while the kernel inlines the equation
modules and takes its layout from rows.py and its options from jit.py: :func:`build_hash`
checks them all, with the host CPU, and :func:`use_current_cache` drops every cached physics
function when it changed. The step kernel compiled ahead of time carries the same hash
(compiled.py).
"""

from __future__ import annotations

import functools
import sys
import zlib
from pathlib import Path

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
