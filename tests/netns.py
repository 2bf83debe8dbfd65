"""Two network namespaces joined by a veth pair, made by the test that needs them and removed
afterwards, so that what crosses them never reaches another address."""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
from typing import Iterator

import pytest


def _ip(*args: str) -> None:
    subprocess.run(["ip", *args], check=True, capture_output=True, timeout=20)


def _listed(*args: str) -> str:
    return subprocess.run(["ip", *args], capture_output=True, text=True, check=True).stdout


@contextlib.contextmanager
def two_namespaces(prefix: str, address: dict[str, str]) -> Iterator[dict[str, str]]:
    """Namespaces ``a`` and ``b`` (their names by side), each with loopback up and its end of
    the link at ``address[side]`` (a /30 pair); skips the test where they cannot be made."""
    if os.geteuid() != 0 or shutil.which("ip") is None:
        pytest.skip("needs root and iproute2 to create network namespaces")
    tag = f"{os.getpid() % 100000}"
    ns = {"a": f"{prefix}_a{tag}", "b": f"{prefix}_b{tag}"}
    veth = {"a": f"{prefix[:4]}va{tag}", "b": f"{prefix[:4]}vb{tag}"}
    try:
        _ip("netns", "add", ns["a"])
        _ip("netns", "add", ns["b"])
        _ip("link", "add", veth["a"], "type", "veth", "peer", "name", veth["b"])
        for side in "ab":
            _ip("link", "set", veth[side], "netns", ns[side])
            _ip("-n", ns[side], "addr", "add", f"{address[side]}/30", "dev", veth[side])
            _ip("-n", ns[side], "link", "set", "lo", "up")
            _ip("-n", ns[side], "link", "set", veth[side], "up")
        yield ns
    finally:
        for side in "ab":
            subprocess.run(["ip", "netns", "del", ns[side]], capture_output=True, timeout=20)
        subprocess.run(["ip", "link", "del", veth["a"]], capture_output=True, timeout=20)
    assert ns["a"] not in _listed("netns", "list") and ns["b"] not in _listed("netns", "list")
    assert veth["a"] not in _listed("-o", "link") and veth["b"] not in _listed("-o", "link")
