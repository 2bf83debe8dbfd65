"""Measured inputs of the diagnosis: unit conversion, tables (three kinds, three delimiters, every
error), and the bag loader on the committed reference bags (alignment, no simulation truth)."""

from __future__ import annotations

import dataclasses
import itertools
import math
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hems_ros.bag import BagWriter, iter_messages, load_bag
from hems_ros.codec import cdr, msgdefs
from hems_ros.diagnosis import bagload, units
from hems_ros.diagnosis.bagload import load_bag_runs, measured_topics
from hems_ros.diagnosis.csvload import DEFAULT_CROSS_SECTION_M2, load_table, parse_columns
from hems_ros.diagnosis.runs import DiagnosisInputError, FeatureRun, TimeSeriesRun
from hems_ros.graph.names import FINGERS

REPO = Path(__file__).resolve().parents[2]
BAGS = {name: REPO / "bags" / name for name in ("ch5_step_index", "demo_grasp_index")}


# -- units -----------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "quantity, unit, value, si",
    [
        ("displacement", "mm", 12.5, 0.0125),
        ("displacement", "um", 250.0, 250e-6),
        ("displacement", "µm", 250.0, 250e-6),
        ("displacement", None, 0.02, 0.02),
        ("stress", "MPa", 150.0, 1.5e8),
        ("stress", "kPa", 2.0, 2000.0),
        ("stress", "GPa", 0.07, 7e7),
        ("temperature", "K", 373.15, 100.0),
        ("temperature", "°C", 70.0, 70.0),
        ("temperature", "C", 70.0, 70.0),
        ("strain", "%", 4.0, 0.04),
        ("strain", "fraction", 0.04, 0.04),
        ("time", "ms", 250.0, 0.25),
        ("time", "min", 1.5, 90.0),
        ("duty", "1", 0.5, 50.0),
        ("duty", "percent", 50.0, 50.0),
        ("current", "mA", 350.0, 0.35),
        ("voltage", "mV", 1200.0, 1.2),
        ("force", "kN", 0.04, 40.0),
        ("load_force", "mN", 500.0, 0.5),
        ("pulse", "ms", 800.0, 0.8),
        ("mean_power", "mW", 1500.0, 1.5),
        ("rmse", "mm", 0.25, 2.5e-4),
    ],
)
def test_conversion_to_si(quantity: str, unit: str | None, value: float, si: float) -> None:
    assert units.to_si(quantity, unit, value) == pytest.approx(si, rel=1e-12)
    assert units.to_si(quantity, unit, np.array([value, value])) == pytest.approx(
        [si, si], rel=1e-12
    )


def test_default_units_and_aliases() -> None:
    assert [
        units.default_unit(q)
        for q in (
            "time",
            "duty",
            "current",
            "voltage",
            "temperature",
            "stress",
            "wire_force",
            "displacement",
            "strain",
        )
    ] == ["s", "%", "A", "V", "degC", "Pa", "N", "m", "1"]
    assert units.canonical("force") == "wire_force" and units.canonical("pulse") == "pulse_length"
    assert units.default_unit("protocol") is None


def test_unknown_unit_and_quantity() -> None:
    with pytest.raises(DiagnosisInputError) as caught:
        units.to_si("displacement", "furlong", 1.0)
    assert str(caught.value) == "unknown unit 'furlong' for displacement (known: m, mm, um, in)"
    with pytest.raises(DiagnosisInputError, match="unknown unit 'mm' for temperature"):
        units.check_unit("temperature", "mm")
    with pytest.raises(DiagnosisInputError, match="unknown quantity 'speed'"):
        units.canonical("speed")
    with pytest.raises(DiagnosisInputError, match="protocol is a text column and takes no unit"):
        units.check_unit("protocol", "s")


# -- column mapping --------------------------------------------------------------------------------


def test_parse_columns() -> None:
    assert parse_columns("time=t:s,current=I:A,displacement=x:mm,force=F:N") == {
        "time": ("t", "s"),
        "current": ("I", "A"),
        "displacement": ("x", "mm"),
        "wire_force": ("F", "N"),
    }
    assert parse_columns(" time = #1 , strain=eps:% ,temperature=T") == {
        "time": ("#1", "s"),
        "strain": ("eps", "%"),
        "temperature": ("T", "degC"),
    }


@pytest.mark.parametrize(
    "spec, message",
    [
        ("time=t,speed=v", "unknown quantity 'speed'"),
        ("time=t,force=F,wire_force=G", "wire_force is mapped twice"),
        ("time=t,displacement", "malformed column mapping 'displacement'"),
        ("time=", "malformed column mapping 'time='"),
        ("=t", "malformed column mapping '=t'"),
        ("time=#0", "malformed column mapping 'time=#0'"),
        ("time=#x", "malformed column mapping 'time=#x'"),
        ("time=t:parsec", "unknown unit 'parsec' for time"),
        ("", "no columns given"),
    ],
)
def test_parse_columns_errors(spec: str, message: str) -> None:
    with pytest.raises(DiagnosisInputError, match=message):
        parse_columns(spec)


# -- tables ----------------------------------------------------------------------------------------


def write(
    tmp_path: Path, name: str, header: str, rows, delimiter: str = ",", comments: str = ""
) -> Path:
    path = tmp_path / name
    lines = [header] + [delimiter.join(str(v) for v in row) for row in rows]
    path.write_text(comments + "\n".join(lines) + "\n", encoding="utf-8")
    return path


def driven_rows(n: int = 101) -> list[tuple]:
    """t ms, I mA, x mm (grows as the wire contracts, from 3 mm), F N."""
    return [(10 * k, 300 if k < 50 else 0, 3.0 + 0.05 * k, 1.0 + 0.1 * k) for k in range(n)]


def test_driven_csv(tmp_path: Path) -> None:
    path = write(tmp_path, "pulse.csv", "t,I,x,F", driven_rows())
    run = load_table(path, "time=t:ms,current=I:mA,displacement=x:mm,force=F:N")
    assert isinstance(run, TimeSeriesRun)
    assert (run.kind, run.drive, run.name, run.source) == ("driven", "current", "pulse", str(path))
    assert run.n_samples == 101 and run.time[0] == 0.0 and run.time[-1] == pytest.approx(1.0)
    assert run.drive_values[0] == pytest.approx(0.3) and run.drive_values[-1] == 0.0
    assert run.outputs["position"][0] == 0.0 and run.outputs["position"][-1] == pytest.approx(5e-3)
    assert run.outputs["wire_force"][-1] == pytest.approx(11.0)
    assert set(run.outputs) == {"position", "wire_force"}


def test_driven_whitespace_table_with_comments_and_index_columns(tmp_path: Path) -> None:
    rows = [
        (1000.0 + 0.05 * k, 0.25 if k % 10 < 5 else 0.0, 4.0 - 0.01 * k, 60.0 + k)
        for k in range(30)
    ]
    path = write(
        tmp_path,
        "duty.txt",
        "time   duty  eps   temp",
        rows,
        delimiter="   ",
        comments="# bench run 3\n#  sampled at 20 Hz\n",
    )
    run = load_table(path, "time=#1,duty=duty:fraction,strain=eps:%,temperature=#4", name="bench 3")
    assert run.name == "bench 3" and run.drive == "duty"
    assert run.time[-1] == pytest.approx(1.45)  # relative to the first row
    assert run.drive_values[:6] == pytest.approx([25, 25, 25, 25, 25, 0])
    assert run.outputs["strain"][-1] == pytest.approx(
        -0.29e-2
    )  # change from the first row, elongation +
    assert run.outputs["temperature"][-1] == pytest.approx(89.0)


def test_thermal_cycle_semicolon_decimal_comma_without_time(tmp_path: Path) -> None:
    temps = [300.15 + 2 * k for k in range(15)] + [328.15 - 2 * k for k in range(1, 15)]
    rows = [
        (f"{t:.2f}".replace(".", ","), f"{4.0 - 0.1 * k:.2f}".replace(".", ","), "150,0")
        for k, t in enumerate(temps)
    ]
    path = write(tmp_path, "cycle.csv", "T;strain;sigma", rows, delimiter=";")
    run = load_table(path, "temperature=T:K,strain=strain:%,stress=sigma:MPa")
    assert (run.kind, run.drive) == ("thermal_cycle", "temperature")
    assert run.drive_values[0] == pytest.approx(27.0) and run.drive_values[14] == pytest.approx(
        55.0
    )
    assert run.stress_pa == pytest.approx(1.5e8)
    assert run.time[:3] == pytest.approx([0.0, 2.0, 4.0]) and run.time[-1] == pytest.approx(56.0)
    assert run.outputs["strain"][-1] == pytest.approx(-2.8e-2)
    assert any("cumulative temperature change at 1 degC per s" in note for note in run.notes)


def test_thermal_cycle_load_force_over_cross_section(tmp_path: Path) -> None:
    rows = [(0.5 * k, 20.0 + k, 0.1 * k, 30.0) for k in range(25)]
    path = write(tmp_path, "wire.csv", "t,T,x,W", rows)
    run = load_table(path, "time=t,temperature=T,displacement=x:mm,load_force=W:N")
    assert run.stress_pa == pytest.approx(30.0 / DEFAULT_CROSS_SECTION_M2)
    assert DEFAULT_CROSS_SECTION_M2 == pytest.approx(2.027e-7, rel=1e-3)
    assert run.outputs["position"][-1] == pytest.approx(2.4e-3) and run.time[-1] == 12.0
    other = load_table(
        path, "time=t,temperature=T,displacement=x:mm,load_force=W:N", cross_section_m2=1e-7
    )
    assert other.stress_pa == pytest.approx(3e8)


def test_feature_table_tab_separated(tmp_path: Path) -> None:
    rows = [
        ("short", 500, 2.0, 10.5, 1.8, 0.45),
        ("", 1000, 1.5, 14.0, 2.6, 0.5),
        ("long", 2000, 1.0, 16.25, 3.9, 0.5),
    ]
    path = write(
        tmp_path, "table43.tsv", "name\tpulse ms\tI\tpeak\tcool\tcooled", rows, delimiter="\t"
    )
    run = load_table(
        path,
        "name=name,pulse=#2:ms,current=I,peak_displacement=peak:mm,cooling_time=cool,"
        "cooled_displacement=cooled:mm",
    )
    assert isinstance(run, FeatureRun) and len(run.tests) == 3
    assert [t.name for t in run.tests] == ["short", "row 3", "long"]
    assert run.tests[0].conditions == pytest.approx(
        {"pulse_s": 0.5, "current_a": 2.0, "cooled_m": 4.5e-4}
    )
    assert run.tests[2].figures == pytest.approx(
        {"peak_displacement": 0.01625, "cooling_time": 3.9}
    )


def test_feature_table_closed_loop(tmp_path: Path) -> None:
    rows = [("step", "bpid", 10.43, 0.72), ("step", "pid", 11.9, 2.5)]
    path = write(tmp_path, "table52.csv", "protocol,controller,rmse,os", rows)
    run = load_table(path, "protocol=protocol,controller=controller,rmse=rmse:mm,overshoot=os:mm")
    assert run.tests[1].conditions == {"protocol": "step", "controller": "pid"}
    assert run.tests[0].figures == pytest.approx({"rmse": 0.01043, "overshoot": 7.2e-4})
    assert run.tests[0].name == "row 2"


# every error names the problem (and the row/column where there is one)
def error_of(path: Path, columns: str, **kwargs) -> str:
    with pytest.raises(DiagnosisInputError) as caught:
        load_table(path, columns, **kwargs)
    message = str(caught.value)
    assert "\n" not in message
    return message


DRIVEN = "time=t:ms,current=I:mA,displacement=x:mm"


def test_file_errors(tmp_path: Path) -> None:
    assert "no such file" in error_of(tmp_path / "absent.csv", DRIVEN)
    assert "cannot read it" in error_of(tmp_path, DRIVEN)
    (tmp_path / "empty.csv").write_text("")
    assert (
        error_of(tmp_path / "empty.csv", DRIVEN)
        == f"{tmp_path / 'empty.csv'}: empty (no header row)"
    )
    (tmp_path / "comments.csv").write_text("# only\n# comments\n\n")
    assert "empty (no header row)" in error_of(tmp_path / "comments.csv", DRIVEN)
    (tmp_path / "header.csv").write_text("t,I,x\n")
    assert "no data rows" in error_of(tmp_path / "header.csv", DRIVEN)
    (tmp_path / "binary.csv").write_bytes(b"\xff\xfe\x00\x81")
    assert "not a UTF-8 text table" in error_of(tmp_path / "binary.csv", DRIVEN)
    ragged = write(tmp_path, "ragged.csv", "t,I,x", [(0, 1, 2), (1, 2)])
    assert "row 3 has 2 fields, the header has 3" in error_of(ragged, DRIVEN)


def test_mapping_errors(tmp_path: Path) -> None:
    path = write(tmp_path, "run.csv", "t,I,V,x", [(10 * k, 100, 1, 0.1 * k) for k in range(101)])
    assert "column 'pos' (for displacement) is not in the header (columns: t, I, V, x)" in error_of(
        path, "time=t,current=I,displacement=pos"
    )
    assert "column #7 (for current) is beyond the header's 4 columns" in error_of(
        path, "time=t,current=#7," "displacement=x"
    )
    assert (
        error_of(path, "current=I,displacement=x")
        == f"{path}: no time column mapped: add time=<column>[:unit] to --columns"
    )
    assert "more than one input mapped (current, voltage)" in error_of(
        path, "time=t,current=I,voltage=V," "displacement=x"
    )
    assert "no output column mapped" in error_of(path, "time=t,current=I")
    assert "no input column mapped" in error_of(path, "time=t,displacement=x")
    assert "stress cannot be mapped in a driven run" in error_of(path, DRIVEN + ",stress=V")
    assert "no figure column mapped" in error_of(path, "pulse=t,current=I")
    assert "map pulse_length" in error_of(path, "current=I,rmse=x")
    assert "time cannot be mapped in a feature table" in error_of(path, "pulse=t,rmse=x,time=t")


def test_unreadable_value_names_row_and_column(tmp_path: Path) -> None:
    rows = driven_rows()
    rows[15] = (rows[15][0], rows[15][1], "abc", rows[15][3])  # file row 17: the header is row 1
    path = write(tmp_path, "run.csv", "t,I,x,F", rows)
    assert error_of(path, DRIVEN) == f"{path}: row 17, column x: 'abc' is not a finite number"
    # an empty cell is a reading not taken at that row: the column's readings around it fill it
    rows[15] = (rows[15][0], rows[15][1], "", rows[15][3])
    run = load_table(write(tmp_path, "gap.csv", "t,I,x,F", rows), DRIVEN)
    assert run.outputs["position"][15] == pytest.approx(0.05e-3 * 15)
    assert "column x: 100 readings in 101 rows" in run.notes[0]


@pytest.mark.parametrize("bad", ["nan", "inf", "-inf"])
def test_a_non_finite_measurement_in_a_table_is_dropped_with_a_note(
    tmp_path: Path, bad: str
) -> None:
    from hems_ros.diagnosis import replay

    full = load_table(write(tmp_path, "full.csv", "t,I,x,F", driven_rows()), DRIVEN)
    rows = driven_rows()
    rows[15] = (rows[15][0], rows[15][1], bad, rows[15][3])
    run = load_table(write(tmp_path, "run.csv", "t,I,x,F", rows), DRIVEN)
    assert run.notes == ("1 samples with column x not a number (NaN or inf) dropped",)
    assert np.array_equal(run.time, np.delete(full.time, 15))
    assert np.array_equal(run.drive_values, np.delete(full.drive_values, 15))
    assert np.array_equal(run.outputs["position"], np.delete(full.outputs["position"], 15))
    # the dropped row's input still drives the model over its interval
    assert np.array_equal(replay.plan(run).values, replay.plan(full).values)


def test_a_non_finite_input_in_a_table_names_row_and_column(tmp_path: Path) -> None:
    rows = driven_rows()
    rows[15] = (rows[15][0], "nan", rows[15][2], rows[15][3])
    path = write(tmp_path, "run.csv", "t,I,x,F", rows)
    assert error_of(path, DRIVEN) == f"{path}: row 17, column I: 'nan' is not a finite number"


def test_a_table_with_many_non_finite_measurements_is_refused(tmp_path: Path) -> None:
    rows = [(t, i, "nan" if 10 <= k < 16 else x, f) for k, (t, i, x, f) in enumerate(driven_rows())]
    path = write(tmp_path, "run.csv", "t,I,x,F", rows)
    assert error_of(path, DRIVEN) == (
        f"{path}: 6 of 101 samples of column x are not a number, more than 5%: the run is refused"
    )
    rows = [(t, i, "nan" if 10 <= k < 15 else x, f) for k, (t, i, x, f) in enumerate(driven_rows())]
    assert load_table(write(tmp_path, "five.csv", "t,I,x,F", rows), DRIVEN).n_samples == 96


def test_units_declared_wrongly_are_caught_naming_the_unit_that_fits(tmp_path: Path) -> None:
    path = write(tmp_path, "run.csv", "t,I,x,F", driven_rows())
    assert error_of(path, "time=t,current=I:mA,displacement=x:mm") == (
        f"{path}: column t: samples 10 s apart (median) over 1000 s, too slow for an "
        f"electrically driven wire: a time in ms declared as s? map it as time=t:ms"
    )
    assert error_of(path, "time=t:ms,current=I,displacement=x:mm") == (
        f"{path}: column I: a current of 300 A, beyond a thin SMA wire's: mA declared as A? "
        f"map it as current=I:mA"
    )
    rows = [(t, i * 1e-3 / 0.4, x, f) for t, i, x, f in driven_rows()]  # duty 0-0.75
    fraction = write(tmp_path, "fraction.csv", "t,d,x,F", rows)
    assert error_of(fraction, "time=t:ms,duty=d,displacement=x:mm") == (
        f"{fraction}: column d: the duty never exceeds 0.75 %: a 0-1 fraction declared as %? "
        f"map it as duty=d:1"
    )
    run = load_table(fraction, "time=t:ms,duty=d:1,displacement=x:mm")
    assert run.drive_values.max() == pytest.approx(75.0)


def test_time_must_increase_strictly(tmp_path: Path) -> None:
    rows = driven_rows()
    rows[40] = (rows[39][0],) + rows[40][1:]
    path = write(tmp_path, "run.csv", "t,I,x,F", rows)
    assert "row 42: time 0.39 s is not after row 41's 0.39 s" in error_of(path, DRIVEN)
    rows[40] = (385,) + rows[40][1:]
    assert "row 42: time 0.385 s is not after row 41's 0.39 s" in error_of(
        write(tmp_path, "b.csv", "t,I,x,F", rows), DRIVEN
    )


def test_runs_too_short(tmp_path: Path) -> None:
    few = write(tmp_path, "few.csv", "t,I,x", [(100 * k, 100, k) for k in range(19)])
    assert "19 samples are too few" in error_of(few, DRIVEN)
    brief = write(tmp_path, "brief.csv", "t,I,x", [(10 * k, 100, k) for k in range(60)])
    assert "the run lasts 0.59 s, too short" in error_of(brief, DRIVEN)
    one = write(tmp_path, "one.csv", "pulse,peak", [(1.0, 2.0)])
    assert "only 1 test row, too few to compare" in error_of(
        one, "pulse=pulse,peak_displacement=peak"
    )


def test_drive_range(tmp_path: Path) -> None:
    rows = [(10 * k, 50, -0.5 if k == 30 else 1.0, k) for k in range(101)]
    rows[20] = (200, 120, 1.0, 20)
    path = write(tmp_path, "run.csv", "t,d,I,x", rows)
    assert (
        error_of(path, "time=t:ms,duty=d,displacement=x")
        == f"{path}: row 22, column d: duty 120 % is outside 0-100 %"
    )
    assert "row 32, column I: negative current -0.5 A" in error_of(
        path, "time=t:ms,current=I,displacement=x"
    )
    assert "row 32, column I: negative voltage -0.5 V" in error_of(
        path, "time=t:ms,voltage=I,displacement=x"
    )


def test_thermal_cycle_whose_stress_wanders_takes_it_row_by_row(tmp_path: Path) -> None:
    rows = [(20.0 + k, 0.1 * k, 150.0 + (4.0 if k == 7 else 0.0)) for k in range(25)]
    path = write(tmp_path, "cycle.csv", "T,eps,sigma", rows)
    run = load_table(path, "temperature=T,strain=eps:%,stress=sigma:MPa")
    assert run.stress_pa == 150e6
    assert run.stress_values[7] == 154e6 and np.all(np.delete(run.stress_values, 7) == 150e6)
    assert "stress 150-154 MPa (mean 150.2, sd 0.784): the model takes it row by row" in run.notes
    steady = load_table(
        write(tmp_path, "steady.csv", "T,eps,sigma", [r[:2] + (150.0,) for r in rows]),
        "temperature=T,strain=eps:%,stress=sigma:MPa",
    )
    assert steady.stress_values is None


def test_prescribed_strain_run_takes_the_frame_strain_in_and_the_force_out(tmp_path: Path) -> None:
    # t ms, I A, frame strain % (from a 1 % pre-stretch), stress MPa
    rows = [(10 * k, 2.0 if k >= 20 else 0.0, 1.0 - 0.01 * k, 200.0 + k) for k in range(150)]
    path = write(tmp_path, "loop.csv", "t,I,eps,sigma", rows)
    columns = "time=t:ms,current=I,prescribed_strain=eps:%,stress=sigma:MPa"
    run = load_table(path, columns, cross_section_m2=2e-7)
    assert (run.kind, run.drive) == ("prescribed_strain", "current")
    assert run.stress_pa == pytest.approx(200e6)
    np.testing.assert_allclose(run.strain_values, -1e-4 * np.arange(150), atol=1e-15)
    np.testing.assert_allclose(run.outputs["wire_force"], (200.0 + np.arange(150)) * 1e6 * 2e-7)
    assert "wire force from the stress column times 2e-07 m2" in run.notes
    # a failed load cell reading drops its row; the strain keeps its own rows
    rows[40] = rows[40][:3] + ("nan",)
    dropped = load_table(write(tmp_path, "gap.csv", "t,I,eps,sigma", rows), columns)
    assert dropped.n_samples == 149 and dropped.strain_values[40] == pytest.approx(-41e-4)
    assert "needs stress=<column>[:unit] or wire_force" in error_of(
        path, "time=t:ms,current=I,prescribed_strain=eps:%"
    )
    assert "displacement cannot be mapped in a prescribed-strain run" in error_of(
        path, columns + ",displacement=eps:mm"
    )
    slack = [(t, i, e, 0.0) for t, i, e, _ in rows]
    assert "the frame must hold the wire under tension from the start" in error_of(
        write(tmp_path, "slack.csv", "t,I,eps,sigma", slack), columns
    )


def test_a_log_with_several_rates_and_a_jittery_clock_loads_with_notes(tmp_path: Path) -> None:
    # rows every 10 ms but every seventh 3 ms late; the current written every fifth row (the
    # cells between empty); the force read at 10 Hz, from row 3 on
    rows = [
        (
            10 * k + (3 if k % 7 == 0 else 0),
            ("0.3" if 50 <= k < 150 else "0") if k % 5 == 0 else "",
            f"{3 + 0.01 * k:.3f}",
            f"{1 + 0.01 * k:.3f}" if k % 10 == 2 else "",
        )
        for k in range(300)
    ]
    path = write(tmp_path, "rates.csv", "t,I,x,F", rows)
    run = load_table(path, "time=t:ms,current=I:A,displacement=x:mm,force=F:N")
    assert run.notes == (
        "rows 7-13 ms apart (median 10 ms): each is read at the plant step nearest its time",
        "column I: 240 empty cells hold the current before them",
        "column F: 30 readings in 300 rows (about 10 Hz), interpolated linearly onto the rows "
        "between them; 9 rows outside them dropped",
    )
    assert run.n_samples == 291
    # the force between two readings lies on the line between them (a straight ramp here)
    times = np.array([r[0] for r in rows], dtype=float)
    read = np.arange(2, 300, 10)
    expected = np.interp(times[2:293], times[read], 1.0 + 0.01 * read)
    np.testing.assert_allclose(run.outputs["wire_force"], expected, atol=1e-12)
    # the current holds from one written cell to the next; the dropped rows still drive
    assert run.drive_values[47:51].tolist() == [0.0, 0.3, 0.3, 0.3]  # row k is sample k - 2
    rows[0] = (0, "", "3.000", "")
    assert "the current is empty in the first row" in error_of(
        write(tmp_path, "late.csv", "t,I,x,F", rows),
        "time=t:ms,current=I:A,displacement=x:mm,force=F:N",
    )


def test_thermal_cycle_errors(tmp_path: Path) -> None:
    rows = [(20.0 + k, 0.1 * k, 150.0) for k in range(25)]
    path = write(tmp_path, "cycle.csv", "T,eps,sigma", rows)
    compression = write(
        tmp_path,
        "compression.csv",
        "T,eps,sigma",
        [(20.0 + k, 0.1 * k, 150.0 - 12 * k) for k in range(25)],
    )
    assert (
        "row 15, column sigma: stress -6e+06 Pa: a thermal cycle needs the wire under tension"
        in error_of(compression, "temperature=T,strain=eps:%,stress=sigma:MPa")
    )
    steady = write(
        tmp_path,
        "steady.csv",
        "T,eps,sigma",
        [(20.0 + k, 0.1 * k, 150.0 + (2.9 if k == 7 else 0)) for k in range(25)],
    )
    assert load_table(
        steady, "temperature=T,strain=eps:%,stress=sigma:MPa"
    ).stress_pa == pytest.approx((150 * 25 + 2.9) / 25 * 1e6)
    assert "exactly one load column" in error_of(path, "temperature=T,strain=eps:%")
    assert "a thermal cycle needs strain" in error_of(path, "temperature=T,stress=sigma:MPa")
    flat = write(
        tmp_path,
        "flat.csv",
        "T,eps,sigma",
        [(20.0 + min(k, 10), 0.1 * k, 150.0) for k in range(25)],
    )
    # without a time column a row that does not move the temperature on is dropped: here
    # fourteen, which leaves too few
    assert "flat.csv: 11 samples are too few" in error_of(
        flat, "temperature=T,strain=eps,stress=sigma"
    )
    plateau = write(
        tmp_path,
        "plateau.csv",
        "T,eps,sigma",
        [(20.0 + k - (k == 7), 0.1 * k, 150.0) for k in range(25)],
    )
    run = load_table(plateau, "temperature=T,strain=eps,stress=sigma")
    assert run.n_samples == 24 and (
        "1 row(s) at the temperature of the row before dropped: without a time column, the path "
        "is the temperature's" in run.notes
    )


# -- bags ------------------------------------------------------------------------------------------


def raw_streams(bag_path: Path) -> dict:
    """The index finger's encoder, duty and wire-force streams, decoded independently of bagload."""
    bag = load_bag(
        bag_path, topics=["/hems/index/encoder", "/hems/index/duty", "/hems/index/wire_force"]
    )

    def ns(data, prefix="header.stamp"):
        return data[f"{prefix}.sec"].astype(np.int64) * 10**9 + data[f"{prefix}.nanosec"]

    encoder, duty, force = (bag[f"/hems/index/{s}"] for s in ("encoder", "duty", "wire_force"))
    return {
        "encoder": ns(encoder),
        "position": encoder["position"],
        "duty_at": ns(duty, "measurement_stamp"),
        "duty": duty["duty_percent"],
        "force_at": ns(force),
        "force": force["force"],
    }


@pytest.fixture(scope="module")
def bag_runs() -> dict[str, TimeSeriesRun]:
    return {name: load_bag_runs(path) for name, path in BAGS.items()}


@pytest.mark.parametrize(
    "name, n_encoder, n_duty, n_force, outside, extra_forces",
    [
        ("ch5_step_index", 1797, 1797, 1812, 0, 15),
        ("demo_grasp_index", 1802, 1820, 1818, 18, 16),
    ],
)
def test_bag_runs_lengths(
    bag_runs, name: str, n_encoder: int, n_duty: int, n_force: int, outside: int, extra_forces: int
) -> None:
    raw = raw_streams(BAGS[name])
    assert (raw["encoder"].size, raw["duty"].size, raw["force"].size) == (
        n_encoder,
        n_duty,
        n_force,
    )
    [run] = bag_runs[name]
    assert (run.name, run.source, run.kind, run.drive) == (
        f"{name}:index",
        f"{BAGS[name]}:index",
        "driven",
        "duty",
    )
    # every encoder sample has its wire force (the sensor stamps the sample it measured)
    assert np.isin(raw["encoder"], raw["force_at"]).all()
    assert (
        run.n_samples
        == n_encoder
        == run.drive_values.size
        == run.outputs["position"].size
        == run.outputs["wire_force"].size
    )
    assert (
        f"{extra_forces} wire forces without an encoder sample at their stamp dropped" in run.notes
    )
    unanswered = f"{outside} duty commands answer no encoder sample of the bag"
    assert any(note.startswith(unanswered) for note in run.notes) == (outside > 0)
    assert np.array_equal(run.time, (raw["encoder"] - raw["encoder"][0]) * 1e-9)
    assert np.diff(run.time) == pytest.approx(0.01, abs=1e-6)
    assert run.duration_s == pytest.approx((n_encoder - 1) * 0.01, abs=1e-5)


@pytest.mark.parametrize("name", sorted(BAGS))
def test_bag_run_alignment_and_values(bag_runs, name: str) -> None:
    raw = raw_streams(BAGS[name])
    [run] = bag_runs[name]
    sample = {stamp: k for k, stamp in enumerate(raw["encoder"])}
    answered = [(sample[s], d) for s, d in zip(raw["duty_at"], raw["duty"]) if s in sample]
    assert len(answered) == raw["encoder"].size  # one duty per sample, stamps equal in ns
    for k, duty in answered:
        assert run.drive_values[k] == duty
    assert run.drive_values.max() == 100.0 and np.count_nonzero(run.drive_values) > 300
    assert run.outputs["position"][0] == 0.0
    assert np.array_equal(run.outputs["position"], raw["position"] - raw["position"][0])
    force_at = dict(zip(raw["force_at"], raw["force"]))
    assert np.array_equal(run.outputs["wire_force"], [force_at[s] for s in raw["encoder"]])
    for values in (run.time, run.drive_values, *run.outputs.values()):
        assert np.isfinite(values).all()
    assert run.resolution == {"position": 1e-6, "wire_force": 0.01}


def test_bag_setpoints_on_the_encoder_time_base(bag_runs) -> None:
    [step] = bag_runs["ch5_step_index"]
    assert [(mode, value) for _, mode, value in step.setpoints] == [
        ("position", 0.0),
        ("position", 0.02),
        ("position", 0.0),
    ]
    times = [t for t, _, _ in step.setpoints]
    assert np.diff(times) == pytest.approx([2.0, 5.0], abs=0.01)  # 20 mm for 5 s after 2 s at 0
    assert 0.0 < times[0] < step.duration_s and times[2] + 8.0 == pytest.approx(
        step.duration_s, abs=1.0
    )
    [grasp] = bag_runs["demo_grasp_index"]
    assert [(mode, value) for _, mode, value in grasp.setpoints] == [
        ("position", 0.02),
        ("force", 10.0),
        ("position", 0.0),
    ]
    assert np.diff([t for t, _, _ in grasp.setpoints]) == pytest.approx([5.0, 6.0], abs=0.01)


def test_no_simulation_topic_is_requested_or_read(monkeypatch: pytest.MonkeyPatch) -> None:
    assert measured_topics(FINGERS) and not [
        t for t in measured_topics(FINGERS) if "/hems/sim/" in t
    ]
    assert measured_topics(["index"]) == [
        "/hems/index/duty",
        "/hems/index/encoder",
        "/hems/index/wire_force",
        "/hems/index/setpoint",
    ]
    requested, read = [], []

    def spy(path, topics=None, regex=None):
        requested.append((list(topics or ()), regex))
        bag = load_bag(path, topics=topics, regex=regex)
        read.extend(bag.topics)
        return bag

    monkeypatch.setattr(bagload, "load_bag", spy)
    for path in BAGS.values():
        load_bag_runs(path)
    assert len(requested) == 2 and all(topics and regex is None for topics, regex in requested)
    assert not [t for topics, _ in requested for t in topics if t.startswith("/hems/sim/")]
    assert set(read) == {
        "/hems/index/duty",
        "/hems/index/encoder",
        "/hems/index/wire_force",
        "/hems/index/setpoint",
    }


def copy_bag(
    source: Path,
    target: Path,
    keep=lambda message, ordinal: True,
    rewrite=None,
    delay=lambda message, ordinal: 0,
) -> Path:
    """``source`` copied message by message into ``target``: the messages for which
    ``keep(message, ordinal on its topic)`` holds, ``rewrite = (topic, data -> data)`` applied,
    logged ``delay(message, ordinal)`` ns later."""
    ordinals: dict[str, int] = {}
    with BagWriter(target) as writer:
        for m in iter_messages(source):
            ordinal = ordinals[m.topic] = ordinals.get(m.topic, -1) + 1
            if not keep(m, ordinal):
                continue
            if rewrite and m.topic == rewrite[0]:
                m = dataclasses.replace(m, data=rewrite[1](m.data))
            writer.write_copy(m, m.log_time_ns + delay(m, ordinal))
    return target


@pytest.mark.parametrize("name", sorted(BAGS))
def test_bag_without_simulation_topics_gives_identical_runs(
    bag_runs, tmp_path: Path, name: str
) -> None:
    copy = copy_bag(BAGS[name], tmp_path / name, lambda m, _: not m.topic.startswith("/hems/sim/"))
    assert not [t for t in load_bag(copy).topics if "/sim/" in t]
    [original], [stripped] = bag_runs[name], load_bag_runs(copy)
    assert stripped.source == f"{copy}:index"
    for field in dataclasses.fields(TimeSeriesRun):
        if field.name == "source":
            continue
        a, b = getattr(original, field.name), getattr(stripped, field.name)
        if isinstance(a, dict):
            assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a), field.name
        elif field.name == "drive_steps":
            assert all(np.array_equal(x, y) for x, y in zip(a, b)), field.name
        else:
            assert np.array_equal(a, b) if isinstance(a, np.ndarray) else a == b, field.name


def test_setpoints_without_header_stamp_take_the_log_time(bag_runs, tmp_path: Path) -> None:
    # CDR: 4 bytes of encapsulation, then header.stamp (sec int32, nanosec uint32)
    copy = copy_bag(
        BAGS["ch5_step_index"],
        tmp_path / "unstamped",
        rewrite=("/hems/index/setpoint", lambda data: data[:4] + bytes(8) + data[12:]),
    )
    [run], [unstamped] = bag_runs["ch5_step_index"], load_bag_runs(copy)
    assert [s[1:] for s in unstamped.setpoints] == [s[1:] for s in run.setpoints]
    # the setpoint tool stamps when it publishes, the recorder logs on reception: under 5 ms apart
    assert [s[0] for s in unstamped.setpoints] == pytest.approx(
        [s[0] for s in run.setpoints], abs=0.005
    )
    assert [s[0] for s in unstamped.setpoints] != [s[0] for s in run.setpoints]


def test_duty_answering_near_a_sample_applies_from_it(bag_runs, tmp_path: Path) -> None:
    raw = raw_streams(BAGS["ch5_step_index"])
    shift_ns = 2_000_000  # under half the 10 ms period

    answered = iter(raw["duty_at"])  # in file order, as the copy meets the messages

    def shifted(data: bytes) -> bytes:
        # measurement_stamp (sec int32, nanosec uint32) comes after the header's stamp
        at = int(next(answered))
        k = data.index(struct.pack("<iI", *divmod(at, 10**9)), 12)
        return data[:k] + struct.pack("<iI", *divmod(at + shift_ns, 10**9)) + data[k + 8 :]

    copy = copy_bag(
        BAGS["ch5_step_index"], tmp_path / "late_stamps", rewrite=("/hems/index/duty", shifted)
    )
    moved = raw_streams(copy)
    assert np.array_equal(moved["duty_at"], raw["duty_at"] + shift_ns)
    [run], [late] = bag_runs["ch5_step_index"], load_bag_runs(copy)
    assert np.array_equal(late.drive_values, run.drive_values)
    assert any(
        note.startswith("1797 duty commands answer no encoder stamp exactly") for note in late.notes
    )


def test_watchdog_zeroes_the_duty_after_three_silent_periods(bag_runs, tmp_path: Path) -> None:
    [run] = bag_runs["ch5_step_index"]
    raw = raw_streams(BAGS["ch5_step_index"])
    # a stretch of 15 samples at nonzero duty; its duties 1-10 lost, as if the controller stalled
    start = next(k for k in range(run.n_samples) if np.all(run.drive_values[k : k + 15] > 0))
    lost = {
        int(np.flatnonzero(raw["duty_at"] == raw["encoder"][k])[0])
        for k in range(start + 1, start + 11)
    }
    copy = copy_bag(
        BAGS["ch5_step_index"],
        tmp_path / "stalled",
        lambda m, ordinal: not (m.topic == "/hems/index/duty" and ordinal in lost),
    )
    [stalled] = load_bag_runs(copy)
    held, tripped = (
        stalled.drive_values[start : start + 3],
        stalled.drive_values[start + 3 : start + 11],
    )
    assert held == pytest.approx([run.drive_values[start]] * 3)  # 10 and 20 ms old: still applied
    assert np.all(tripped == 0.0) and np.all(run.drive_values[start + 3 : start + 11] > 0)
    assert stalled.drive_values[start + 11] == run.drive_values[start + 11]
    assert (
        "watchdog: 8 samples more than 3 periods after the last duty command, at 0 %"
        in stalled.notes
    )


def test_missing_force_samples_are_dropped_and_leave_a_gap(bag_runs, tmp_path: Path) -> None:
    [run] = bag_runs["ch5_step_index"]
    raw = raw_streams(BAGS["ch5_step_index"])
    lost = {int(np.flatnonzero(raw["force_at"] == raw["encoder"][k])[0]) for k in (500, 501, 502)}
    copy = copy_bag(
        BAGS["ch5_step_index"],
        tmp_path / "lossy",
        lambda m, ordinal: not (m.topic == "/hems/index/wire_force" and ordinal in lost),
    )
    [lossy] = load_bag_runs(copy)
    assert lossy.n_samples == run.n_samples - 3
    assert lossy.time[500] - lossy.time[499] == pytest.approx(0.04, abs=1e-6)  # the gap stays a gap
    assert np.array_equal(lossy.drive_values, np.delete(run.drive_values, [500, 501, 502]))
    assert "3 encoder samples without a wire force at their stamp dropped" in lossy.notes
    assert not np.isnan(lossy.outputs["wire_force"]).any()


def test_cut_bag_loads_as_far_as_it_goes(bag_runs, tmp_path: Path) -> None:
    [run] = bag_runs["ch5_step_index"]
    data = (BAGS["ch5_step_index"] / "ch5_step_index_0.mcap").read_bytes()
    (tmp_path / "cut").mkdir()
    (tmp_path / "cut" / "cut_0.mcap").write_bytes(data[: len(data) * 6 // 10])
    [cut] = load_bag_runs(tmp_path / "cut")
    assert cut.name == "cut:index" and 100 < cut.n_samples < run.n_samples
    assert any(
        note.startswith("bag cut or unfinished, loaded as far as it goes") for note in cut.notes
    )
    n = cut.n_samples
    assert np.array_equal(cut.drive_values[: n - 1], run.drive_values[: n - 1])
    assert np.array_equal(cut.outputs["position"], run.outputs["position"][:n])


def test_bag_errors(tmp_path: Path) -> None:
    with pytest.raises(DiagnosisInputError) as caught:
        load_bag_runs(BAGS["ch5_step_index"], fingers=["index", "middle"])
    assert str(caught.value) == (
        f"{BAGS['ch5_step_index']}: no /hems/middle/duty or /hems/middle/encoder "
        f"messages in the bag (fingers with duty and encoder messages: index)"
    )
    only_index = load_bag_runs(BAGS["ch5_step_index"], fingers=["index"])
    assert [r.name for r in only_index] == ["ch5_step_index:index"]
    with pytest.raises(DiagnosisInputError, match="unknown finger 'pinky'"):
        load_bag_runs(BAGS["ch5_step_index"], fingers=["pinky"])
    (tmp_path / "text").mkdir()
    (tmp_path / "text" / "text_0.mcap").write_text("not a bag at all\n" * 10)
    with pytest.raises(DiagnosisInputError, match="not a readable bag"):
        load_bag_runs(tmp_path / "text")
    (tmp_path / "nothing").mkdir()
    with pytest.raises(DiagnosisInputError, match="not a readable bag"):
        load_bag_runs(tmp_path / "nothing")
    with pytest.raises(DiagnosisInputError, match="not a readable bag"):
        load_bag_runs(tmp_path / "absent")
    with BagWriter(tmp_path / "empty"):
        pass
    with pytest.raises(
        DiagnosisInputError, match="no finger has duty and encoder messages in the bag"
    ):
        load_bag_runs(tmp_path / "empty")
    only_sim = copy_bag(
        BAGS["ch5_step_index"], tmp_path / "only_sim", lambda m, _: m.topic.startswith("/hems/sim")
    )
    with pytest.raises(
        DiagnosisInputError,
        match=r"no finger has duty and encoder messages in the bag \(read: nothing\)",
    ):
        load_bag_runs(only_sim)


def set_field(source: Path, topic: str, field: str, value, ordinals: set[int]):
    """A ``copy_bag`` rewrite of ``topic``: ``field`` set to ``value`` in its messages at these
    ordinals (file order), written with the type's definition stored in the bag (the committed
    bags predate fields the installed messages have)."""
    first = next(m for m in iter_messages(source) if m.topic == topic)
    name = msgdefs.full_name(first.type)
    types = msgdefs.parse_full_definition(first.type, first.definition)
    decoder, encoder = cdr.build_decoder(name, types), cdr.build_encoder(name, types)
    column = [c.name for c in decoder.columns].index(field)
    counter = itertools.count()

    def rewrite(data: bytes) -> bytes:
        if next(counter) not in ordinals:
            return data
        values = list(decoder.decode(data))
        values[column] = value
        return encoder.encode(tuple(values))

    return rewrite


@pytest.mark.parametrize(
    "topic, field, value",
    [
        ("/hems/index/encoder", "position", float("nan")),
        ("/hems/index/wire_force", "force", float("inf")),
    ],
)
def test_a_non_finite_measurement_is_dropped_with_a_note(
    bag_runs, tmp_path: Path, topic: str, field: str, value: float
) -> None:
    [run] = bag_runs["ch5_step_index"]
    raw = raw_streams(BAGS["ch5_step_index"])
    ordinal = 700
    stamp = raw["encoder" if field == "position" else "force_at"][ordinal]
    k = int(np.searchsorted(np.unique(raw["encoder"]), stamp))
    copy = copy_bag(
        BAGS["ch5_step_index"],
        tmp_path / "bad",
        rewrite=(topic, set_field(BAGS["ch5_step_index"], topic, field, value, {ordinal})),
    )
    [bad] = load_bag_runs(copy)
    note = f"1 samples with {topic} {field} not a number (NaN or inf) dropped"
    assert note in bad.notes
    assert bad.n_samples == run.n_samples - 1
    assert np.array_equal(bad.time, np.delete(run.time, k))
    assert np.array_equal(bad.drive_values, np.delete(run.drive_values, k))
    for name, values in run.outputs.items():
        assert np.array_equal(bad.outputs[name], np.delete(values, k)), name


def test_a_run_with_many_non_finite_positions_is_refused(tmp_path: Path) -> None:
    topic = "/hems/index/encoder"
    nan_at = set(range(300, 400))
    copy = copy_bag(
        BAGS["ch5_step_index"],
        tmp_path / "failing_encoder",
        rewrite=(topic, set_field(BAGS["ch5_step_index"], topic, "position", math.nan, nan_at)),
    )
    with pytest.raises(
        DiagnosisInputError,
        match=r"100 of 1797 samples of /hems/index/encoder position are not a number, "
        r"more than 5%: the run is refused",
    ):
        load_bag_runs(copy)


@pytest.mark.parametrize("value", [150.0, -1.0, float("nan")])
def test_a_duty_outside_its_range_names_topic_and_message(tmp_path: Path, value: float) -> None:
    raw = raw_streams(BAGS["ch5_step_index"])
    topic = "/hems/index/duty"
    copy = copy_bag(
        BAGS["ch5_step_index"],
        tmp_path / "bad_duty",
        rewrite=(topic, set_field(BAGS["ch5_step_index"], topic, "duty_percent", value, {1000})),
    )
    at = (raw["duty_at"][1000] - raw["encoder"].min()) * 1e-9
    with pytest.raises(DiagnosisInputError) as caught:
        load_bag_runs(copy)
    assert str(caught.value) == (
        f"{copy}: /hems/index/duty message 1001 of 1797 (answering the encoder sample at "
        f"{at:.3f} s) has duty_percent = {value!r}: a duty is a number within 0-100 %"
    )


def test_short_bag_is_too_short(tmp_path: Path) -> None:
    # the first 60 encoder samples; the wire force has 15 samples before the encoder's first
    copy = copy_bag(BAGS["ch5_step_index"], tmp_path / "short", lambda m, ordinal: ordinal < 60)
    with pytest.raises(
        DiagnosisInputError, match=r"short:index: the run lasts 0.44 s, too short to compare"
    ):
        load_bag_runs(copy)


def test_the_loaders_import_neither_rclpy_nor_numba() -> None:
    """Reading a lab's files needs no ROS and compiles no kernel (the wire's parameters load
    without the physics kernels)."""
    code = (
        "import sys, hems_ros.diagnosis.units, hems_ros.diagnosis.csvload, "
        "hems_ros.diagnosis.bagload; print(sorted(m for m in sys.modules if m.startswith(('rclpy', "
        "'numba', 'hems_ros.physics.kernel'))))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, check=True
    )
    assert result.stdout.strip() == "[]"


def test_a_late_duty_command_applies_from_its_arrival(bag_runs, tmp_path: Path) -> None:
    """The unit applies a command that arrives after the next sample from its arrival (the
    recorder's log time standing in for it); an on-time one from the sample it answers."""
    [run] = bag_runs["ch5_step_index"]
    times, levels = run.drive_steps
    on_samples = np.searchsorted(times, run.time + 1e-9, side="right") - 1
    assert np.array_equal(levels[on_samples], run.drive_values)  # the committed bag: all on time
    k = next(k for k in range(100, run.n_samples) if run.drive_values[k] != run.drive_values[k - 1])
    raw = raw_streams(BAGS["ch5_step_index"])
    ordinal = int(np.flatnonzero(raw["duty_at"] == raw["encoder"][k])[0])
    copy = copy_bag(
        BAGS["ch5_step_index"],
        tmp_path / "late",
        delay=lambda m, o: 15_000_000 if m.topic == "/hems/index/duty" and o == ordinal else 0,
    )
    [late] = load_bag_runs(copy)
    t_late, v_late = late.drive_steps
    start = t_late[np.flatnonzero(v_late == run.drive_values[k])]
    assert np.any(np.abs(start - run.time[k] - 0.015) < 0.003)  # from its arrival, ~15 ms on
    assert not np.any(np.abs(start - run.time[k]) < 1e-9)  # not from its sample
    assert any(
        n.startswith("1 duty commands reached the unit after the next sample") for n in late.notes
    )


def test_displacement_is_measured_from_the_lead_in_at_rest(tmp_path: Path) -> None:
    """A noisy displacement sensor: the zero is the mean of the rows before the drive comes on,
    not the first reading (one noise sample would shift the whole run)."""
    rows = ["t,d,x"] + [
        f"{k * 0.01:.2f},0,{0.004 if k == 0 else (-0.001 if k % 2 else 0.001)}" for k in range(50)
    ]
    rows += [f"{k * 0.01:.2f},100,{1.0 + 0.5 * (k - 50) * 0.01}" for k in range(50, 200)]
    path = tmp_path / "noisy.csv"
    path.write_text("\n".join(rows) + "\n")
    run = load_table(path, "time=t:s,duty=d:%,displacement=x:mm")
    lead = np.array([0.004] + [(-0.001 if k % 2 else 0.001) for k in range(1, 50)]) * 1e-3
    assert run.outputs["position"][0] == pytest.approx(0.004e-3 - lead.mean(), abs=1e-12)
    assert run.outputs["position"][50] == pytest.approx(1.0e-3 - lead.mean(), abs=1e-12)
