"""A suite case gives the same outcome to the last digit on every scheduler: serial in
this process, a local cluster of one worker and of two, and separate `dask scheduler` and
`dask worker` processes in two network namespaces (a cluster of two hosts)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import suite_client
from netns import two_namespaces

from hems_ros.processes import stop_processes

DASK = Path(sys.executable).with_name("dask")
ADDRESS = {"a": "10.232.0.1", "b": "10.232.0.2"}
PORT = 8786


@pytest.fixture(scope="module")
def serial(tmp_path_factory) -> list[dict]:
    return suite_client.records(suite_client.run("serial", tmp_path_factory.mktemp("serial")))


def test_one_and_two_local_workers_give_the_serial_outcomes(serial, tmp_path):
    assert [r["verdict"] for r in serial] == ["named"]
    for workers in (1, 2):
        report = suite_client.run("local", tmp_path / str(workers), workers)
        assert report.workers == workers
        assert suite_client.records(report) == serial


@pytest.mark.slow
def test_workers_on_another_host_give_the_serial_outcomes(serial, tmp_path):
    with two_namespaces("hdask", ADDRESS) as ns:
        address = f"tcp://{ADDRESS['a']}:{PORT}"

        def start(side: str, *args: str) -> subprocess.Popen:
            return subprocess.Popen(
                ["ip", "netns", "exec", ns[side], str(DASK), *args, "--no-dashboard"],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                process_group=0,
            )

        processes = [start("a", "scheduler", "--host", ADDRESS["a"], "--port", str(PORT))]
        try:
            processes.append(
                start(
                    "b",
                    "worker",
                    address,
                    "--host",
                    ADDRESS["b"],
                    "--nworkers",
                    "2",
                    "--nthreads",
                    "1",
                )
            )
            client = subprocess.run(
                [
                    "ip",
                    "netns",
                    "exec",
                    ns["a"],
                    sys.executable,
                    suite_client.__file__,
                    address,
                    str(tmp_path / "cluster"),
                ],
                capture_output=True,
                text=True,
                timeout=300,
            )
        finally:
            stop_processes(processes, 5.0)
    assert client.returncode == 0, client.stderr[-3000:]
    result = json.loads(client.stdout.strip().splitlines()[-1])
    assert result["records"] == serial
    assert result["workers"] >= 1 and result["where"] == [f"tcp://{ADDRESS['b']}"]
