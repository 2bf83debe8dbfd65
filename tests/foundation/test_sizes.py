"""Modules stay under 600 lines and functions under 100. The ones that do not are listed
here with the reason; the list must match the code, so a new long one fails and a shortened
one must leave the list."""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
MODULE_LINES = 600
FUNCTION_LINES = 100
ROOTS = ("hems_ros", "benchmarks", "tools")

LONG_MODULES = {
    "hems_ros/physics/params.py": "the typed parameters of every block of chapter 4's model",
    "hems_ros/diagnosis/csvload.py": "one loader per lab table format, with their checks",
}
LONG_FUNCTIONS = {
    "hems_ros/physics/kernel.py:begin": "one numba step's start: every flow of the step",
    "hems_ros/cli/diagnose.py:register": "the argparse declarations of the diagnose verbs",
    "hems_ros/reports/diagnosis_suite.py:_joint_section": "page text",
    "hems_ros/reports/findings.py:ch5_findings": "the chapter 5 claims, one after the other",
    "benchmarks/bench_physics.py:main": "the benchmark's measurements printed side by side",
    "benchmarks/bench_diagnose.py:write_bag": "a bag of every topic the diagnosis reads",
    "benchmarks/bench_diagnose.py:main": "the benchmark's measurements printed side by side",
    "benchmarks/bench_graph_joins.py:run": "one join of each kind in turn",
}


def _sources():
    for root in ROOTS:
        for path in sorted((REPO / root).rglob("*.py")):
            yield str(path.relative_to(REPO)), path.read_text()


def test_modules_over_600_lines_are_the_listed_ones():
    long = {name for name, text in _sources() if text.count("\n") > MODULE_LINES}
    assert long == set(LONG_MODULES)


def test_functions_over_100_lines_are_the_listed_ones():
    long = {
        f"{name}:{node.name}"
        for name, text in _sources()
        for node in ast.walk(ast.parse(text))
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
        and node.end_lineno - node.lineno + 1 > FUNCTION_LINES
    }
    assert long == set(LONG_FUNCTIONS)
