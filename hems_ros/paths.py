"""Where the project's configuration files are: the checkout's ``config/`` when running from
the source tree, else ``share/hems_ros/config`` of the installation (setup.py installs it)."""

from __future__ import annotations

import sys
from pathlib import Path

_SOURCE_CONFIG = Path(__file__).resolve().parent.parent / "config"


def config_path(*parts: str) -> Path:
    """``config/<parts>`` of the source tree if it exists there, else of the installation."""
    source = _SOURCE_CONFIG.joinpath(*parts)
    if source.exists():
        return source
    return Path(sys.prefix, "share", "hems_ros", "config", *parts)
