"""Code stays in its layer: the plain-Python core imports no ROS, library code imports no
command-line verb, benchmarks and tests reach the graph through the client package, and the
nodes take the message codec from its own package (only the recorder writes bags)."""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
CORE = (
    "physics",
    "control",
    "graph",
    "diagnosis",
    "experiments",
    "bag",
    "codec",
    "reports",
    "truth",
)
ROS = (
    "rclpy",
    "hems_msgs",
    "std_msgs",
    "sensor_msgs",
    "diagnostic_msgs",
    "std_srvs",
    "rosgraph_msgs",
    "rcl_interfaces",
    "builtin_interfaces",
)


def _imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def _is_verb(name: str) -> bool:
    return name == "hems_ros.cli" or name.startswith("hems_ros.cli.")


def _offenders(paths, bad) -> list[str]:
    return sorted(
        f"{p.relative_to(REPO)}: {name}" for p in paths for name in _imports(p) if bad(name)
    )


def test_the_core_imports_no_ros() -> None:
    paths = [p for layer in CORE for p in (REPO / "hems_ros" / layer).rglob("*.py")]
    assert not _offenders(paths, lambda n: n.split(".")[0] in ROS)


def test_graph_client_and_benchmarks_import_no_node() -> None:
    """The rclpy helpers live in hems_ros.ros; a node module is imported only to run it."""
    paths = [
        *(REPO / "hems_ros" / "graph").rglob("*.py"),
        *(REPO / "hems_ros" / "client").rglob("*.py"),
        *(REPO / "hems_ros" / "ros").rglob("*.py"),
        *(REPO / "benchmarks").glob("*.py"),
    ]
    assert not _offenders(paths, lambda n: n == "hems_ros.nodes" or n.startswith("hems_ros.nodes."))


def test_verbs_import_a_node_module_only_to_run_that_node() -> None:
    """`hems record` runs the recorder node and `hems ping` the ping responder (whose topic
    and scales it shares); no other verb imports a node module."""
    runners = {"record.py", "ping.py"}
    paths = [p for p in (REPO / "hems_ros" / "cli").rglob("*.py") if p.name not in runners]
    assert not _offenders(paths, lambda n: n == "hems_ros.nodes" or n.startswith("hems_ros.nodes."))


def test_benchmarks_import_the_installed_package_not_a_patched_path() -> None:
    assert not [
        p.name for p in (REPO / "benchmarks").glob("*.py") if "sys.path.insert" in p.read_text()
    ]


def test_library_code_imports_no_verb() -> None:
    paths = [
        p
        for p in (REPO / "hems_ros").rglob("*.py")
        if "cli" not in p.relative_to(REPO / "hems_ros").parts
    ]
    allowed = {"hems_ros/executables.py"}  # the console-script table names the verbs' entry point
    assert not [o for o in _offenders(paths, _is_verb) if o.split(":")[0] not in allowed]


def test_benchmarks_use_the_client_package_not_the_verbs() -> None:
    paths = list((REPO / "benchmarks").glob("*.py"))
    assert not _offenders(paths, _is_verb)


# the tests of the verbs themselves: argument parsing, formatting, the verb run in-process
VERB_TESTS = {
    "tests/bag/test_replay.py",
    "tests/diagnosis/test_cli.py",
    "tests/foundation/test_cli_help.py",
    "tests/fuzz/test_fuzz_inputs.py",
    "tests/graph/test_status_client.py",
}


def test_tests_use_the_client_package_except_the_tests_of_the_verbs() -> None:
    paths = [
        p for p in (REPO / "tests").rglob("*.py") if str(p.relative_to(REPO)) not in VERB_TESTS
    ]
    assert not _offenders(paths, _is_verb)


def test_of_the_nodes_only_the_recorder_imports_the_bag_package() -> None:
    paths = [p for p in (REPO / "hems_ros" / "nodes").glob("*.py") if p.name != "recorder.py"]
    assert not _offenders(paths, lambda n: n == "hems_ros.bag" or n.startswith("hems_ros.bag."))


def test_reports_sit_above_the_analyses() -> None:
    paths = [
        p
        for layer in ("physics", "control", "diagnosis", "experiments", "graph")
        for p in (REPO / "hems_ros" / layer).rglob("*.py")
    ]
    assert not _offenders(
        paths, lambda n: n == "hems_ros.reports" or n.startswith("hems_ros.reports.")
    )


def test_the_truths_share_no_code_with_the_model_they_test() -> None:
    """Runs made by the project's own model can only show that the fit agrees with itself."""
    paths = list((REPO / "hems_ros" / "truth").rglob("*.py"))
    assert not _offenders(
        paths, lambda n: n.startswith("hems_ros") and not n.startswith("hems_ros.truth")
    )
