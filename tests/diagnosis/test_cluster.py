"""The task runner of the suite and of lab archives (hems_ros.diagnosis.cluster): the same
results on every scheduler, a worker killed mid-task costs only its tasks, a killed run
continues where it stopped."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import cloudpickle
import cluster_tasks
import pytest

from hems_ros.diagnosis import cluster

# the workers of a cluster cannot import the tests' modules by name
cloudpickle.register_pickle_by_value(cluster_tasks)


def test_serial_and_local_cluster_give_every_result_in_the_tasks_order(tmp_path):
    tasks = cluster_tasks.squares(6)
    serial = cluster.run_tasks(tasks, tmp_path / "serial", scheduler=cluster.SERIAL)
    local = cluster.run_tasks(tasks, tmp_path / "local", workers=2)
    assert serial.results() == local.results() == [0, 1, 4, 9, 16, 25]
    assert (serial.workers, local.workers) == (1, 2)
    assert {d.where for d in serial.done.values()} == {"here"}
    assert all(d.where.startswith("tcp://127.0.0.1:") for d in local.done.values())
    assert sorted(p.name for p in (tmp_path / "local").iterdir()) == sorted(
        f"square{i}.pkl" for i in range(6)
    )


def test_local_workers_fork_from_the_preloaded_server(tmp_path):
    tasks = [cluster.Task("parent", cluster_tasks.parent_command, (0,))]
    [command] = cluster.run_tasks(tasks, tmp_path, workers=1).results()
    assert "from multiprocessing.forkserver import main" in command
    # Dask and the first local cluster's task modules of this process, imported once
    assert "['distributed', 'numpy', '" in command


def test_local_workers_run_with_dask_housekeeping_quieted(tmp_path):
    # the profiler, ticks and monitors a worker would otherwise run beside its task
    tasks = [cluster.Task("settings", cluster_tasks.worker_settings, (0,))]
    [seen] = cluster.run_tasks(tasks, tmp_path, workers=1).results()
    assert seen == cluster.QUIET
    assert seen["distributed.worker.profile.enabled"] is False


def test_a_worker_killed_mid_task_costs_only_its_tasks_which_run_again(tmp_path):
    lines = []
    tasks = cluster_tasks.squares(8, die_once=str(tmp_path / "died"), seconds=0.2)
    report = cluster.run_tasks(tasks, tmp_path / "out", workers=2, say=lines.append)
    assert report.results() == [i * i for i in range(8)]
    assert (tmp_path / "died").exists()
    assert report.retried and any(
        "square3: attempt 1 failed (its worker died)" in r for r in report.retried
    )
    # the other worker's tasks were not run again
    assert len(report.retried) <= 2
    assert any("submitted again" in line for line in lines)


def test_a_task_that_raises_stops_the_run_with_its_own_error_on_every_scheduler(tmp_path):
    tasks = [cluster.Task("bad", cluster_tasks.fails, (4,))]
    for scheduler in (cluster.LOCAL, cluster.SERIAL):
        with pytest.raises(ValueError, match="no square for 4"):
            cluster.run_tasks(tasks, tmp_path / scheduler, scheduler=scheduler, workers=1)


def test_a_killed_run_continues_where_it_stopped(tmp_path):
    out = tmp_path / "out"
    script = Path(cluster_tasks.__file__)
    run = subprocess.Popen([sys.executable, str(script), str(out), "12"], stdout=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    while len(list(out.glob("*.pkl"))) < 4 and time.monotonic() < deadline:
        time.sleep(0.05)
    run.send_signal(signal.SIGKILL)
    run.wait(10)
    kept = len(list(out.glob("*.pkl")))
    assert 4 <= kept < 12
    lines = []
    report = cluster.run_tasks(
        cluster_tasks.squares(12), out, scheduler=cluster.SERIAL, say=lines.append
    )
    assert report.resumed == kept
    assert lines[0] == f"resuming: {kept} of 12 tasks already done in {out}"
    assert report.results() == [i * i for i in range(12)]
    # only the missing ones ran
    assert len([line for line in lines if line.startswith("[")]) == 12 - kept


def test_a_result_file_cut_short_is_run_again(tmp_path):
    cluster.run_tasks(cluster_tasks.squares(3), tmp_path, scheduler=cluster.SERIAL)
    (tmp_path / "square1.pkl").write_bytes(b"\x80\x04truncated")
    report = cluster.run_tasks(cluster_tasks.squares(3), tmp_path, scheduler=cluster.SERIAL)
    assert report.resumed == 2 and report.results() == [0, 1, 4]


def test_bad_schedulers_and_keys_are_refused(tmp_path):
    with pytest.raises(ValueError, match="scheduler 'mpi': serial, local or tcp://HOST:PORT"):
        cluster.run_tasks(cluster_tasks.squares(1), tmp_path, scheduler="mpi")
    assert cluster.scheduler_error("tcp://10.0.0.1") is not None  # no port
    assert cluster.scheduler_error("tcp://10.0.0.1:8786") is None
    twice = [cluster.Task("same", cluster_tasks.square, (1,))] * 2
    with pytest.raises(ValueError, match="task keys must be unique"):
        cluster.run_tasks(twice, tmp_path)
