"""The soak's measures (hems_ros.graph.soak) on numbers whose answer is known."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from hems_ros.bag.reader import Bag, TopicData
from hems_ros.graph import soak


def _topic(name: str, **fields) -> TopicData:
    n = len(next(iter(fields.values())))
    return TopicData(
        name,
        "x",
        np.arange(n, dtype=np.int64),
        np.arange(n, dtype=np.int64),
        {k: np.asarray(v) for k, v in fields.items()},
    )


def test_sequence_losses_count_the_missing_numbers_and_restarts():
    assert soak.sequence_losses(np.array([1, 2, 3, 4])) == (0, 0)
    assert soak.sequence_losses(np.array([1, 2, 5, 6, 9])) == (4, 0)
    assert soak.sequence_losses(np.array([7, 8, 1, 2, 4])) == (1, 1)  # a restarted publisher
    assert soak.sequence_losses(np.array([3])) == (0, 0)


def test_bag_losses_leave_out_shared_topics_and_unnumbered_ones():
    bag = Bag(
        Path("b"),
        {
            "/hems/index/encoder": _topic("/hems/index/encoder", sequence=[1, 2, 4]),
            "/hems/index/commands": _topic("/hems/index/commands", sequence=[1, 5]),
            "/hems/joint_states": _topic("/hems/joint_states", position=[0.0, 1.0]),
        },
        [],
    )
    assert soak.bag_losses(bag) == {"/hems/index/encoder": 1}
    # the step to the third message (logged at 2 ns) lost one: after a warm-up to 2 ns, not
    # before it
    assert soak.bag_losses(bag, since_ns=2) == {"/hems/index/encoder": 1}
    assert soak.bag_losses(bag, since_ns=3) == {"/hems/index/encoder": 0}
    assert soak.bag_losses(bag, until_ns=2) == {"/hems/index/encoder": 0}


def test_missed_periods_are_encoder_samples_no_duty_answered():
    stamps = np.arange(100, 110)
    answered = np.array([101, 102, 104, 105, 106, 108])  # 103 and 107 unanswered
    bag = Bag(
        Path("b"),
        {
            "/hems/index/encoder": _topic(
                "/hems/index/encoder",
                **{"header.stamp.sec": stamps, "header.stamp.nanosec": np.zeros(10, int)},
            ),
            "/hems/index/duty": _topic(
                "/hems/index/duty",
                **{
                    "measurement_stamp.sec": answered,
                    "measurement_stamp.nanosec": np.zeros(6, int),
                },
            ),
        },
        [],
    )
    # samples before the first and after the last answer are outside the controlled span
    assert soak.missed_periods(bag, "index") == (2, 8)
    assert soak.missed_periods(bag, "middle") == (0, 0)
    # after a warm-up ending at 105 s: 107 only, of 105-108
    assert soak.missed_periods(bag, "index", since_ns=105 * 10**9) == (1, 4)
    # and before it: 103 of 101-104
    assert soak.missed_periods(bag, "index", until_ns=105 * 10**9) == (1, 4)


def test_memory_growth_is_judged_after_the_warm_up_on_the_last_quarter():
    log = soak.MemoryLog()
    for t in range(0, 100, 10):
        log.add("unit", t, 200 if t < 30 else 100 + (t >= 70) * 4)  # warm-up falls, then +4 %
        log.add("gone", t, None)
    start, end, growth = log.growth(30.0)["unit"]
    assert (start, end) == (100, 104) and abs(growth - 0.04) < 1e-12
    assert "gone" not in log.growth(30.0)


def test_a_result_fails_on_each_limit_it_breaks():
    result = soak.SoakResult(
        1.0, 3, 2, [], {"unit": (100, 104, 0.04)}, {"/e": 0}, {"index": (4, 1000)}, "b"
    )
    assert result.failures() == []
    assert "| control periods missed after warm-up | 4 of 1000 (0.400 %) |" in result.markdown()
    assert "| control periods missed in start-up and warm-up | 0 of 0 | - |" in result.markdown()
    assert "| messages lost in the bag after warm-up (sequence gaps) | 0 | 0 |" in result.markdown()
    result.memory["supervisor"] = (100, 106, 0.06)
    result.losses["/e"] = 2
    result.faults.append("index: encoder lost")
    failures = " | ".join(result.failures())
    assert (
        "1 faults" in failures
        and "2 messages lost" in failures
        and "supervisor resident memory grew 6.0 %" in failures
    )


def test_rss_of_this_process_is_read_and_a_gone_one_is_none():
    assert soak.rss_bytes(os.getpid()) > 10 * 2**20
    assert soak.rss_bytes(2**22 + 12345) is None
