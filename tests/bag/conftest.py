"""Fixtures of the bag tests; shared builders live in bag_helpers.py."""

from __future__ import annotations

from pathlib import Path

import pytest
from bag_helpers import write_bag


@pytest.fixture
def bag_folder(tmp_path: Path) -> tuple[Path, dict[str, list]]:
    folder = tmp_path / "sample"
    return folder, write_bag(folder)
