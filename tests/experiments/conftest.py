"""Lockstep runs shared by the tests: chapter 5 (15 runs) and chapter 6 (8 runs) once
per test run."""

from __future__ import annotations

import pytest

from hems_ros.experiments import chapters
from hems_ros.physics import load_params
from hems_ros.reports import findings


# "package" scope: the folders hold no __init__.py, so one instance serves this folder
# and every folder below it, the whole test run
@pytest.fixture(scope="package")
def ch5_runs():
    return chapters.run_ch5()


@pytest.fixture(scope="package")
def ch6_runs():
    return chapters.run_ch6()


@pytest.fixture(scope="package")
def ch5_found(ch5_runs):
    return {f.key: f for f in findings.ch5_findings(ch5_runs, load_params(chapters.CH5_PARAMS))}


@pytest.fixture(scope="package")
def ch6_found(ch6_runs):
    return {f.key: f for f in findings.ch6_findings(ch6_runs)}
