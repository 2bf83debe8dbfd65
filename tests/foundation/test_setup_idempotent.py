"""`make setup` on a set-up checkout has nothing left to build."""

import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def test_second_make_setup_has_nothing_to_rebuild():
    result = subprocess.run(
        ["make", "--no-print-directory", "--dry-run", "setup"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    commands = [line for line in result.stdout.splitlines() if line.strip()]
    assert commands == ["tools/check_system.sh python3.11"], commands


def test_missing_system_tools_are_named_with_their_debian_package():
    result = subprocess.run(
        ["tools/check_system.sh", "no-such-python3.11"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode != 0
    assert "no-such-python3.11 (Debian package: python3.11)" in result.stderr
