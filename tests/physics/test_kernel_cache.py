"""The kernel's cache check runs when a run builds its first parameter row, not at import."""

from __future__ import annotations

import subprocess
import sys

SCRIPT = """
from hems_ros.physics import kernel, load_params
print(kernel._cache_checked)
kernel.pack(load_params("table41"))
print(kernel._cache_checked)
"""


def test_importing_the_kernel_leaves_its_cache_alone_until_the_first_pack():
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "True"]
