"""Tables measured on different rigs diagnose one wire: each table's rows run on its rig."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hems_ros.diagnosis import dissertation, features, inputs, joint
from hems_ros.diagnosis.runs import FeatureRun, FeatureTest
from hems_ros.paths import config_path
from hems_ros.physics.params import load_params

WIRE = load_params("table41")
ROWS = [(1.2, 4.0), (1.6, 4.0), (2.0, 3.5), (2.4, 3.5)]


def _pulses(truth, name: str, rig=()) -> FeatureRun:
    shells = [FeatureTest(f"{p:g} s", {"pulse_s": p, "current_a": a}, {}) for p, a in ROWS]
    figures = features._pulse_figures([truth], shells, features.PULSE_DT)
    tests = tuple(FeatureTest(t.name, t.conditions, f) for t, f in zip(shells, figures))
    return FeatureRun(name, "made", tests, rig=tuple(rig))


def test_each_table_runs_on_its_own_rig() -> None:
    folder = config_path("measurements")
    ch3, ch5 = inputs.rig(folder / "ch3_rig.yaml"), inputs.rig(folder / "ch5_rig.yaml")
    on_ch3 = _pulses(WIRE.replace(dict(ch3)), "ch3", ch3)
    on_ch5 = _pulses(WIRE.replace(dict(ch5)), "ch5", ch5)
    data = features.prepare([on_ch3, on_ch5], [])
    [own] = data.predict([WIRE])
    assert np.all(own.train == 0.0) and np.all(own.heldout == 0.0)
    # the rigs differ enough to matter: the 40 N mass stretches the wire further than the
    # 30 N mass and 20 N spring, so each table needs its own
    crossed = features.prepare([dataclasses.replace(on_ch3, rig=ch5)], [])
    [wrong] = crossed.predict([WIRE])
    assert np.abs(wrong.train).max() > 5.0


def test_a_rig_file_that_names_no_parameter_is_refused(tmp_path) -> None:
    (tmp_path / "bad.yaml").write_text("load: {mass: 3}\n")
    with pytest.raises(Exception, match="unknown parameter load.mass"):
        WIRE.replace(dict(inputs.rig(tmp_path / "bad.yaml")))


@pytest.mark.parametrize("study", dissertation.STUDIES, ids=lambda s: s.key)
def test_every_calibrated_set_already_stands_on_its_tables_rig(study) -> None:
    """The rig files describe the rigs the calibrated sets were made for: setting one on its
    set changes nothing, so the joint model and the sets are compared on the same rigs."""
    calibrated = load_params(study.calibrated)
    rig = dict(inputs.rig(config_path("measurements") / study.rig))
    assert calibrated.replace(rig) == calibrated
    assert WIRE.replace(rig).load == calibrated.load


def test_the_joint_tables_carry_their_rigs() -> None:
    tables = joint.joint_tables()
    assert [t.name for t in tables] == [s.key for s in dissertation.STUDIES]
    assert [len(t.tests) for t in tables] == [6, 4, 4]
    assert all(t.rig for t in tables)
    data = features.prepare(tables, [])
    # fourteen rows: every third from the second selects, every third from the third tests
    assert int(data.split.heldout[0].sum()) == 5 and int(data.split.test[0].sum()) == 4


def _pull(key: str, value: float, low: float, high: float) -> joint.Pull:
    study = next(s for s in dissertation.STUDIES if s.key == key)
    return joint.Pull(study, "warm_start", {"start.temperature_offset_c": (value, low, high)}, ())


def test_tables_whose_intervals_do_not_overlap_pull_a_term_apart() -> None:
    pulls = [
        _pull("tables_3_2_3_3", 55.0, 52.0, 58.0),
        _pull("chapter_5", 57.0, 56.0, 59.0),
        _pull("table_6_1", 20.0, 15.0, 25.0),
    ]
    apart = joint.apart(pulls)
    assert [(k, a.study.key, b.study.key) for k, a, b in apart] == [
        ("start.temperature_offset_c", "tables_3_2_3_3", "table_6_1"),
        ("start.temperature_offset_c", "chapter_5", "table_6_1"),
    ]
