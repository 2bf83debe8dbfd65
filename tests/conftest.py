"""Test-run environment: DDS on loopback only, the project's Fast DDS settings and a ROS
domain of this run's own.

The test process's own participants (the clients that observe a graph) take the Fast DDS
profiles file that every process of the graph and every `hems` command takes: a participant
without it makes its shared-memory port with Fast DDS's default health check (1000 ms), and a
writer that opens such a port may wait a third of that for its listener, which no user's
process does.

The domain id is reserved with an exclusive lock file for the whole run, so two test
runs on one machine (a developer's and CI's, say) never share a DDS domain. It is set
in ``os.environ`` before any test starts, so every child process inherits it.
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

# the hook below is found by its name in this module: every test runs under the hang guard
from hang_guard import live_descendants, pytest_runtest_protocol  # noqa: F401

REPO = Path(__file__).resolve().parent.parent
VENV = REPO / ".venv"
_domain_lock = None
# multiprocessing's helpers of this process, started with Dask's first local cluster
HELPERS = (
    "from multiprocessing.resource_tracker import main",
    "from multiprocessing.forkserver import main",
)


def pytest_configure(config: pytest.Config) -> None:
    from hems_ros.rosenv import apply_network_defaults, reserve_domain_id

    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    apply_network_defaults()
    global _domain_lock
    if "HEMS_TEST_DOMAIN_ID" not in os.environ:
        domain, _domain_lock = reserve_domain_id()
        os.environ["HEMS_TEST_DOMAIN_ID"] = str(domain)
    os.environ["ROS_DOMAIN_ID"] = os.environ["HEMS_TEST_DOMAIN_ID"]


#: Folders whose tests only compute (no graph, no ROS process unless they ask for the domain).
COMPUTING_FOLDERS = {"physics", "control", "diagnosis", "truth", "experiments", "fuzz"}
#: ... and single files elsewhere that only compute.
COMPUTING_FILES = {"test_lint.py", "test_cli_help.py"}


def computes_only(item: pytest.Item) -> bool:
    path = Path(item.path)
    return (
        path.parent.name in COMPUTING_FOLDERS or path.name in COMPUTING_FILES
    ) and "ros_domain_id" not in getattr(item, "fixturenames", ())


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """``HEMS_TEST_PART=computing`` or ``ros`` keeps one side of the split
    tools/run_tests_in_two.sh runs as two processes side by side."""
    part = os.environ.get("HEMS_TEST_PART")
    if part is None:
        return
    if part not in ("computing", "ros"):
        raise pytest.UsageError(f"HEMS_TEST_PART={part!r}: expected 'computing' or 'ros'")
    kept: list[pytest.Item] = []
    dropped: list[pytest.Item] = []
    for item in items:
        (kept if computes_only(item) == (part == "computing") else dropped).append(item)
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = kept


def pytest_unconfigure(config: pytest.Config) -> None:
    if _domain_lock is not None:
        _domain_lock.close()  # releases the domain for the next run


# "package" scope: the folders hold no __init__.py, so one instance serves this folder
# and every folder below it, the whole test run
@pytest.fixture(scope="package")
def ros_domain_id() -> int:
    """The DDS domain this test run owns (also in ``os.environ['ROS_DOMAIN_ID']``)."""
    return int(os.environ["ROS_DOMAIN_ID"])


@pytest.fixture(scope="package")
def venv() -> Path:
    if not (VENV / "bin" / "python").exists():
        pytest.fail(f"{VENV} is missing: run `make setup`")
    return VENV


@pytest.fixture(scope="module", autouse=True)
def no_process_outlives_its_module():
    """A node a test module left running would join every later test's graph in this
    domain (a second controller answering the same samples); kill it and say which."""
    yield
    left = {
        pid: command
        for pid, command in live_descendants(os.getpid()).items()
        # they live as long as the test run and restart if killed
        if not any(helper in command for helper in HELPERS)
    }
    if not left:
        return
    for pid in left:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    time.sleep(0.2)  # gone before the next module starts its graph
    pytest.fail(
        "processes left running by this module (killed now): "
        + "; ".join(f"{pid} {command[:160]}" for pid, command in sorted(left.items()))
    )
