"""Measured tables (CSV, semicolon, tab or whitespace separated) as diagnosis runs.

``--columns`` maps quantities to columns: ``time=t:s,current=I:A,displacement=x:mm``
(``quantity=column[:unit]``; a column is a header name or a 1-based index ``#3``; a unit
left out is the quantity's default, :mod:`hems_ros.diagnosis.units`). What is mapped decides
the kind of run:

- a feature table (any feature quantity mapped): one :class:`FeatureTest` per row;
- a driven run: time, exactly one of duty/current/voltage, and at least one output;
- a thermal cycle: temperature and none of duty/current/voltage, strain or displacement, and
  the load (stress, or load_force/wire_force over the wire's cross-section); a load that
  wanders by more than ``STRESS_TOLERANCE`` of its mean, as a frame's does, drives the model
  row by row.

Conventions of the columns: displacement increases when the wire contracts (the encoder's
sign); strain is the wire's strain, elongation positive. Both become changes from the run's
lead-in at rest (the mean of the rows before the drive first comes on, at most a second; the
first row of a thermal cycle). Rows are numbered as in the file (the header's line is row 1 when
nothing precedes it), so an error's row is the line an editor shows. A table whose delimiter is not
the comma may use decimal commas (``1,5``).

A measured column's cell written ``nan`` or ``inf`` (a logger's value for a failed reading) drops
its row with a note, the row's input still driving the model over its interval; more than
``runs.MAX_BAD_SHARE`` of the rows so refuses the run. Any other cell that is not a finite
number, in an input column any non-finite one, is an error naming row and column.

A load frame's export: lines above the header (the test method, the sample; up to
``MAX_METADATA_LINES``) are read past, a row quoted whole is split at its delimiters, and a
thermal cycle's time printed coarser than its rows come is spread evenly between its stamps;
an extension becomes strain over the gauge length, rows that still load the wire are left
out. A file without a header row (every cell of the first line a number) names its columns
by index. Each leaves a note.

Logs with several rates: in a run with a time column, an empty cell of a measured column is a
reading not taken at that row (the column is logged more slowly): the column's readings are
interpolated linearly onto the rows between them, and rows before its first or after its last
reading are dropped. An empty input cell holds the input before it. Rows unevenly spaced are
read at the plant steps nearest their times. Each of these leaves a note.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hems_ros.diagnosis import units
from hems_ros.diagnosis.runs import (
    FIGURE_UNITS,
    DiagnosisInputError,
    FeatureRun,
    FeatureTest,
    TimeSeriesRun,
    non_finite_note,
)
from hems_ros.physics.params import WireGeometry

# the HEMS wire of Table 4.1 (the parameters load without the physics kernels)
DEFAULT_CROSS_SECTION_M2 = WireGeometry().cross_section_m2
DEFAULT_GAUGE_LENGTH_M = WireGeometry().length_m
MIN_SAMPLES = 20
MIN_DRIVEN_S = 1.0
MIN_TESTS = 2
STRESS_TOLERANCE = 0.02
#: Lines of a load frame's export above its header (test method, sample, units) read past.
MAX_METADATA_LINES = 40
#: A thermal cycle whose last temperature is within this of its first closes (degC).
CLOSED_C = 1.0
#: A driven run sampled slower than this (median step) is no record of an electrically heated
#: wire, whose thermal time constants are about a second: most likely a time in ms declared as s.
MAX_DRIVEN_STEP_S = 1.0
#: Inputs beyond these are not a thin SMA wire's: mA or mV declared as A or V.
MAX_INPUT = {"current": 20.0, "voltage": 100.0}
#: Drive at or below which a run's lead-in counts as at rest (% duty, A, V).
LEAD_IN_OFF = {"duty": 0.5, "current": 0.05, "voltage": 0.1}

DRIVE_QUANTITIES = ("duty", "current", "voltage")
#: time series quantity -> TimeSeriesRun output name
OUTPUTS = {
    "displacement": "position",
    "strain": "strain",
    "extension": "extension",  # a thermal cycle's, turned into strain over the gauge length
    "wire_force": "wire_force",
    "load_force": "load_force",
    "temperature": "temperature",
}
#: feature table quantity -> FeatureTest condition name
CONDITIONS = {
    "pulse_length": "pulse_s",
    "current": "current_a",
    "energy": "energy_j",
    "cooled_displacement": "cooled_m",
    "protocol": "protocol",
    "controller": "controller",
}
FEATURE_QUANTITIES = (
    "pulse_length",
    "energy",
    "cooled_displacement",
    "protocol",
    "controller",
    *FIGURE_UNITS,
)
LOAD_QUANTITIES = ("stress", "load_force", "wire_force")

Columns = dict[str, tuple[str, str | None]]


def parse_columns(spec: str) -> Columns:
    """``quantity=column[:unit],...`` -> {canonical quantity: (column, canonical unit)}."""
    mapping: Columns = {}
    if not spec or not spec.strip():
        raise DiagnosisInputError(
            "no columns given: expected quantity=column[:unit],... "
            "(e.g. time=t:s,current=I:A,displacement=x:mm)"
        )
    for item in spec.split(","):
        quantity, equals, target = (part.strip() for part in item.strip().partition("="))
        column, _, unit = target.rpartition(":") if ":" in target else (target, "", "")
        column, unit = column.strip(), unit.strip()
        if (
            not equals
            or not quantity
            or not column
            or (column.startswith("#") and not _index_ok(column))
        ):
            raise DiagnosisInputError(
                f"malformed column mapping {item.strip()!r}: expected "
                f"quantity=column[:unit] (column: a header name or #<1-based index>)"
            )
        name = units.canonical(quantity)
        if name in mapping:
            raise DiagnosisInputError(
                f"{name} is mapped twice in the columns " f"({mapping[name][0]!r} and {column!r})"
            )
        mapping[name] = (column, units.check_unit(name, unit))
    return mapping


def _index_ok(column: str) -> bool:
    return column[1:].isdigit() and int(column[1:]) >= 1


@dataclass(frozen=True)
class _Table:
    path: Path
    header: list[str]
    rows: list[tuple[int, list[str]]]  # (row number in the file, fields)
    decimal_comma: bool
    notes: tuple[str, ...] = ()  # how the file was read (metadata lines, no header)

    def where(self, row: int, index: int) -> str:
        return f"{self.path}: row {row}, column {self.header[index]}"


def _split(line: str, delimiter: str | None) -> list[str]:
    fields = line.split() if delimiter is None else next(csv.reader([line], delimiter=delimiter))
    if delimiter is not None and len(fields) == 1 and delimiter in fields[0]:
        # a row quoted whole, as some load-frame software exports them
        fields = next(csv.reader([fields[0]], delimiter=delimiter))
    return [f.strip() for f in fields]


def _trim(fields: list[str], width: int) -> list[str]:
    """Drop empty fields past ``width``: a trailing delimiter is no column (an empty field within
    the header's width is an empty cell)."""
    while len(fields) > width and not fields[-1]:
        fields.pop()
    return fields


def _delimiter(line: str) -> str | None:
    counts = {d: line.count(d) for d in (",", ";", "\t")}
    return max(counts, key=counts.__getitem__) if any(counts.values()) else None


def _is_number(text: str) -> bool:
    try:
        float(text.replace(",", "."))
    except ValueError:
        return False
    return True


def _header_at(lines: list[tuple[int, str]]) -> int | None:
    """The line of the header under an export's metadata: the first of two or more names, none a
    number, over a row as wide whose cells are mostly numbers; None when no line is one."""
    for i in range(min(len(lines) - 1, MAX_METADATA_LINES + 1)):
        delimiter = _delimiter(lines[i][1])
        head = _trim(_split(lines[i][1], delimiter), 0)
        below = _trim(_split(lines[i + 1][1], delimiter), len(head))
        if (
            len(head) >= 2
            and len(below) == len(head)
            and not any(_is_number(f) for f in head)
            and 2 * sum(_is_number(f) for f in below) > len(below)
        ):
            return i
    return None


def _read(path: Path) -> _Table:
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise DiagnosisInputError(f"{path}: no such file") from None
    except UnicodeDecodeError:
        raise DiagnosisInputError(f"{path}: not a UTF-8 text table") from None
    except OSError as error:
        raise DiagnosisInputError(f"{path}: cannot read it ({error.strerror or error})") from None
    lines = [
        (n, line)
        for n, line in enumerate(text.splitlines(), 1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not lines:
        raise DiagnosisInputError(f"{path}: empty (no header row)")
    notes = []
    at = _header_at(lines)
    delimiter = _delimiter(lines[at or 0][1])
    first = _split(lines[0][1], delimiter)
    if at is None and all(_is_number(f) for f in first):
        header, body = [f"#{k}" for k in range(1, len(first) + 1)], lines
        notes.append("no header row: columns by index (#1, #2 ...)")
    else:
        at = at or 0
        header, body = _trim(_split(lines[at][1], delimiter), 0), lines[at + 1 :]
        if at:
            notes.append(
                f"{at} line(s) above the header (lines {lines[0][0]}-{lines[at - 1][0]}) "
                "read as the export's metadata"
            )
    rows = []
    for number, line in body:
        fields = _trim(_split(line, delimiter), len(header))
        if len(fields) != len(header):
            raise DiagnosisInputError(
                f"{path}: row {number} has {len(fields)} fields, the header has {len(header)}"
            )
        rows.append((number, fields))
    if not rows:
        raise DiagnosisInputError(f"{path}: no data rows below the header")
    return _Table(path, header, rows, delimiter != ",", tuple(notes))


def _column_index(table: _Table, quantity: str, column: str) -> int:
    if column.startswith("#"):
        index = int(column[1:]) - 1
        if index >= len(table.header):
            raise DiagnosisInputError(
                f"{table.path}: column {column} (for {quantity}) is beyond the "
                f"header's {len(table.header)} columns ({', '.join(table.header)})"
            )
        return index
    if column not in table.header:
        raise DiagnosisInputError(
            f"{table.path}: column {column!r} (for {quantity}) is not in the header "
            f"(columns: {', '.join(table.header)})"
        )
    if table.header.count(column) > 1:
        raise DiagnosisInputError(
            f"{table.path}: column {column!r} (for {quantity}) appears twice in the "
            f"header; give it by index (#<n>)"
        )
    return table.header.index(column)


def _texts(table: _Table, quantity: str, column: str) -> list[str]:
    index = _column_index(table, quantity, column)
    return [fields[index] for _, fields in table.rows]


def _numbers(
    table: _Table,
    quantity: str,
    column: str,
    unit: str | None,
    blanks: bool = False,
    measured: bool = False,
) -> np.ndarray:
    """A numeric column in SI; every value must be a finite number (``blanks``: an empty cell
    is a figure the table does not give, NaN; ``measured``: a nan or inf written in the cell,
    a sensor's failure value, is kept for the caller to drop)."""
    index = _column_index(table, quantity, column)
    values = np.empty(len(table.rows))
    for k, (number, fields) in enumerate(table.rows):
        text = fields[index]
        if blanks and not text.strip():
            values[k] = math.nan
            continue
        if table.decimal_comma and "," in text and "." not in text:
            text = text.replace(",", ".")
        try:
            values[k] = float(text)
        except ValueError:
            values[k] = math.nan
            measured_failure = False
        else:
            measured_failure = measured
        if not math.isfinite(values[k]) and not measured_failure:
            raise DiagnosisInputError(
                f"{table.where(number, index)}: {fields[index]!r} " f"is not a finite number"
            )
    values = units.to_si(quantity, unit, values)
    _check_range(table, quantity, index, values[np.isfinite(values)])
    return values


def _check_range(table: _Table, quantity: str, index: int, values: np.ndarray) -> None:
    if quantity == "duty":
        bad = np.flatnonzero((values < 0.0) | (values > 100.0))
        problem = "duty {:g} % is outside 0-100 %"
    elif quantity in ("current", "voltage"):
        bad = np.flatnonzero(values < 0.0)
        problem = f"negative {quantity} {{:g}} {units.default_unit(quantity)}"
    else:
        return
    if bad.size:
        first = int(bad[0])
        raise DiagnosisInputError(
            f"{table.where(table.rows[first][0], index)}: " f"{problem.format(values[first])}"
        )


def _restrict(columns: Columns, allowed: tuple[str, ...], kind: str, path: Path) -> None:
    extra = [q for q in columns if q not in allowed]
    if extra:
        raise DiagnosisInputError(
            f"{path}: {', '.join(extra)} cannot be mapped in {kind} "
            f"(it takes {', '.join(allowed)})"
        )


def require_span(source: str, time: np.ndarray, kind: str) -> None:
    """A time series too short to say anything is an error: under 20 samples, or a driven run
    under 1 s (shared with the bag loader)."""
    if time.size < MIN_SAMPLES:
        raise DiagnosisInputError(
            f"{source}: {time.size} samples are too few to compare "
            f"(a time series needs at least {MIN_SAMPLES})"
        )
    duration = float(time[-1] - time[0])
    if kind == "driven" and duration < MIN_DRIVEN_S:
        raise DiagnosisInputError(
            f"{source}: the run lasts {duration:g} s, too short to compare "
            f"(a driven run needs at least {MIN_DRIVEN_S:g} s)"
        )


def _check_time(table: _Table, time: np.ndarray, index_text: str) -> None:
    steps = np.diff(time)
    bad = np.flatnonzero(steps <= 0.0)
    if bad.size:
        k = int(bad[0]) + 1
        raise DiagnosisInputError(
            f"{table.path}: row {table.rows[k][0]}: time {time[k]:g} s is not after "
            f"row {table.rows[k - 1][0]}'s {time[k - 1]:g} s "
            f"({index_text} must increase strictly)"
        )


def _untied(time: np.ndarray, notes: list[str]) -> np.ndarray:
    """A thermal cycle's time printed coarser than its rows come (a frame's export in hours to
    three decimals): the rows of each stamp spread evenly up to the next stamp. A time that
    goes back is left for :func:`_check_time` to refuse."""
    steps = np.diff(time)
    if np.all(steps > 0.0) or np.any(steps < 0.0):
        return time
    stamps, first, counts = np.unique(time, return_index=True, return_counts=True)
    ends = np.r_[stamps[1:], stamps[-1] + np.median(np.diff(stamps))]
    out = time.astype(float)
    for stamp, i, n, end in zip(stamps, first, counts, ends):
        out[i : i + n] = stamp + (end - stamp) * np.arange(n) / n
    notes.append(
        f"{int(np.sum(steps == 0.0))} row(s) at the time of the row before (time printed to "
        f"{np.min(np.diff(stamps)):.3g} s): each stamp's rows spread evenly up to the next"
    )
    return out


def load_table(
    path,
    columns: str | Mapping[str, tuple[str, str | None]],
    name: str | None = None,
    cross_section_m2: float = DEFAULT_CROSS_SECTION_M2,
    gauge_length_m: float = DEFAULT_GAUGE_LENGTH_M,
) -> TimeSeriesRun | FeatureRun:
    """Read a measured table and convert it to SI and the runs' conventions (module docstring).

    ``columns`` is a ``--columns`` string or what :func:`parse_columns` returns;
    ``cross_section_m2`` turns a thermal cycle's load force into stress, ``gauge_length_m``
    its extension into strain.
    """
    path = Path(path)
    if isinstance(columns, str):
        columns = parse_columns(columns)
    else:
        columns = {units.canonical(q): (c, units.check_unit(q, u)) for q, (c, u) in columns.items()}
    table = _read(path)
    name = name or path.stem
    if any(q in FEATURE_QUANTITIES for q in columns):
        return _features(table, columns, name)
    drives = [q for q in DRIVE_QUANTITIES if q in columns]
    if len(drives) > 1:
        raise DiagnosisInputError(
            f"{path}: more than one input mapped ({', '.join(drives)}): "
            f"a driven run has exactly one of {', '.join(DRIVE_QUANTITIES)}"
        )
    if "prescribed_strain" in columns:
        heating = drives[0] if drives else "temperature" if "temperature" in columns else None
        if heating is None:
            raise DiagnosisInputError(
                f"{path}: a prescribed-strain run needs what heats the wire: one of "
                f"{', '.join(DRIVE_QUANTITIES)}, or temperature (a chamber's)"
            )
        return _prescribed_strain(table, columns, name, heating, cross_section_m2)
    if drives:
        return _driven(table, columns, name, drives[0])
    if "temperature" in columns:
        return _thermal_cycle(table, columns, name, cross_section_m2, gauge_length_m)
    raise DiagnosisInputError(
        f"{path}: no input column mapped: map one of {', '.join(DRIVE_QUANTITIES)} "
        f"(a driven run) or temperature alone (a thermal cycle), or feature columns "
        f"({', '.join(FEATURE_QUANTITIES)})"
    )


def _outputs(
    table: _Table,
    columns: Columns,
    quantities: tuple[str, ...],
    rest: int = 1,
    time: np.ndarray | None = None,
) -> tuple[dict[str, np.ndarray], np.ndarray, list[str]]:
    """The mapped outputs, the rows where each is a number, and the notes on those that are
    not (a nan or inf written in a measured column: the row is dropped). Displacement and
    strain as changes from their mean over the first ``rest`` rows (the run's lead-in at
    rest): one noisy first reading would shift the whole run. With the rows' ``time``, a
    column with empty cells is a slower channel of a log with several rates (:func:`_slower`)."""
    outputs, keep, notes = {}, np.ones(len(table.rows), dtype=bool), list(table.notes)
    for quantity in quantities:
        if quantity in columns:
            values = _numbers(table, quantity, *columns[quantity], blanks=True, measured=True)
            if time is not None:
                values = _slower(table, columns[quantity][0], time, values, keep, notes)
            elif _blank(table, columns[quantity][0]).any():
                raise DiagnosisInputError(
                    f"{table.path}: column {columns[quantity][0]} has empty cells: a table "
                    f"without a time column cannot say when its readings were taken"
                )
            finite = np.isfinite(values)
            notes += non_finite_note(str(table.path), f"column {columns[quantity][0]}", finite)
            keep &= finite
            if quantity in ("displacement", "strain", "extension"):
                lead_in = values[:rest][finite[:rest]]
                values = values - float(np.mean(lead_in if lead_in.size else values[finite][:1]))
            outputs[OUTPUTS[quantity]] = values
    return outputs, keep, notes


def _blank(table: _Table, column: str) -> np.ndarray:
    index = _column_index(table, "", column)
    return np.array([not fields[index].strip() for _, fields in table.rows])


def _slower(
    table: _Table,
    column: str,
    time: np.ndarray,
    values: np.ndarray,
    keep: np.ndarray,
    notes: list[str],
) -> np.ndarray:
    """A column logged more slowly than the rows (empty cells between its readings): its
    readings linearly interpolated onto the rows between them; rows before its first reading
    or after its last are dropped (``keep``)."""
    blank = _blank(table, column)
    if not blank.any():
        return values
    read = np.flatnonzero(~blank)
    if read.size < 2:
        raise DiagnosisInputError(f"{table.path}: column {column} holds fewer than two readings")
    finite = read[np.isfinite(values[read])]
    filled = values.copy()
    # rows outside the readings take the nearest one only to be dropped below
    filled[blank] = np.interp(time[blank], time[finite], values[finite])
    row = np.arange(values.size)
    outside = blank & ((row < read[0]) | (row > read[-1]))
    keep &= ~outside
    rate = 1.0 / float(np.median(np.diff(time[read])))
    notes.append(
        f"column {column}: {read.size} readings in {values.size} rows (about {rate:.3g} Hz), "
        f"interpolated linearly onto the rows between them"
        + (f"; {int(outside.sum())} rows outside them dropped" if outside.any() else "")
    )
    return filled


def _kept(
    time: np.ndarray, outputs: dict[str, np.ndarray], keep: np.ndarray
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Time (from the first kept row) and outputs on the kept rows."""
    time = time[keep]
    return time - time[0], {name: values[keep] for name, values in outputs.items()}


def _lead_in(time: np.ndarray, drive: np.ndarray, drive_name: str) -> int:
    """Rows before the drive first comes on, at most the first second (at least one row)."""
    on = np.flatnonzero(np.abs(drive) > LEAD_IN_OFF[drive_name])
    first = int(on[0]) if on.size else time.size
    return max(1, min(first, int(np.searchsorted(time, time[0] + 1.0))))


def _driven(table: _Table, columns: Columns, name: str, drive: str) -> TimeSeriesRun:
    _restrict(columns, ("time", drive, *OUTPUTS), "a driven run", table.path)
    if not any(q in columns for q in OUTPUTS) and "time" in columns:
        raise DiagnosisInputError(
            f"{table.path}: no output column mapped: add one of {', '.join(OUTPUTS)} "
            f"to --columns"
        )
    time, values, notes = _driven_input(table, columns, drive)
    outputs, keep, more = _outputs(
        table, columns, tuple(OUTPUTS), rest=_lead_in(time, values, drive), time=time
    )
    notes += more
    _check_plausible(table, columns, time, drive, values)
    # a dropped row's interval keeps its own input
    steps = None if keep.all() else (time - time[keep][0], values)
    kept_time, outputs = _kept(time, outputs, keep)
    require_span(str(table.path), kept_time, "driven")
    return TimeSeriesRun(
        name=name,
        source=str(table.path),
        kind="driven",
        time=kept_time,
        drive=drive,
        drive_values=values[keep],
        outputs=outputs,
        notes=tuple(notes),
        drive_steps=steps,
    )


def _held(table: _Table, drive: str, spec: tuple[str, str | None], notes: list[str]) -> np.ndarray:
    """The input column; an empty cell (a log that writes the input only when it changes, or
    at a slower rate) holds the value before it, as the drive board holds a command."""
    values = _numbers(table, drive, *spec, blanks=True)
    blank = np.isnan(values)
    if blank[0]:
        raise DiagnosisInputError(
            f"{table.where(table.rows[0][0], _column_index(table, drive, spec[0]))}: the "
            f"{drive} is empty in the first row: there is no value before it to hold"
        )
    if blank.any():
        last = np.maximum.accumulate(np.where(blank, 0, np.arange(values.size)))
        values = values[last]
        notes.append(
            f"column {spec[0]}: {int(blank.sum())} empty cells hold the {drive} before them"
        )
    return values


def _sampling_notes(time: np.ndarray) -> list[str]:
    """A note when the rows are not evenly spaced (a logger's jitter, a pause)."""
    steps = np.diff(time)
    median = float(np.median(steps))
    if steps.min() >= 0.9 * median and steps.max() <= 1.1 * median:
        return []
    return [
        f"rows {steps.min() * 1e3:.3g}-{steps.max() * 1e3:.3g} ms apart (median "
        f"{median * 1e3:.3g} ms): each is read at the plant step nearest its time"
    ]


def _driven_input(
    table: _Table, columns: Columns, drive: str
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Time (from the first row) and input of an electrically driven run, checked, with the
    notes on their sampling."""
    if "time" not in columns:
        raise DiagnosisInputError(
            f"{table.path}: no time column mapped: add time=<column>[:unit] to --columns"
        )
    time = _numbers(table, "time", *columns["time"])
    _check_time(table, time, "time")
    time = time - time[0]
    require_span(str(table.path), time, "driven")
    notes = _sampling_notes(time)
    return time, _held(table, drive, columns[drive], notes), notes


def _prescribed_strain(
    table: _Table, columns: Columns, name: str, drive: str, cross_section_m2: float
) -> TimeSeriesRun:
    """A load frame moves the wire's end (prescribed_strain in) while the drive heats it (or a
    chamber sets its temperature): the wire's force (or stress over the cross-section) comes
    out."""
    path = table.path
    _restrict(
        columns,
        ("time", drive, "prescribed_strain", "stress", "wire_force", "temperature"),
        "a prescribed-strain run",
        path,
    )
    if not {"stress", "wire_force"} & set(columns) and "time" in columns:
        raise DiagnosisInputError(
            f"{path}: no output column mapped: a prescribed-strain run needs "
            f"stress=<column>[:unit] or wire_force=<column>[:unit] in --columns"
        )
    time, values, notes = _driven_input(table, columns, drive)
    if drive != "temperature":  # a chamber's run may be slow; its checks are the thermal's
        _check_plausible(table, columns, time, drive, values)
    strain = _numbers(table, "prescribed_strain", *columns["prescribed_strain"])
    measured = tuple(q for q in ("wire_force", "temperature") if q != drive)
    outputs, keep, more = _outputs(table, columns, measured, time=time)
    notes += more
    if "stress" in columns:
        stress = _numbers(table, "stress", *columns["stress"], measured=True)
        finite = np.isfinite(stress)
        notes += non_finite_note(str(path), f"column {columns['stress'][0]}", finite)
        keep &= finite
        outputs["wire_force"] = stress * cross_section_m2
        notes.append(f"wire force from the stress column times {cross_section_m2:.4g} m2")
    if not keep[0]:
        raise DiagnosisInputError(
            f"{table.where(table.rows[0][0], 0)}: the first row must hold the preload "
            f"(the model starts from it)"
        )
    preload = float(outputs["wire_force"][0]) / cross_section_m2
    if not preload > 0:
        raise DiagnosisInputError(
            f"{path}: a preload of {preload:.4g} Pa in the first row: the frame must hold "
            f"the wire under tension from the start"
        )
    steps = None if keep.all() else (time, values)
    kept_time, outputs = _kept(time, outputs, keep)
    require_span(str(path), kept_time, "driven")
    return TimeSeriesRun(
        name=name,
        source=str(path),
        kind="prescribed_strain",
        time=kept_time,
        drive=drive,
        drive_values=values[keep],
        outputs=outputs,
        stress_pa=preload,
        strain_values=(strain - strain[0])[keep],
        notes=tuple(notes),
        drive_steps=steps,
    )


def _check_plausible(
    table: _Table, columns: Columns, time: np.ndarray, drive: str, values: np.ndarray
) -> None:
    """Catch a unit declared wrongly, naming the column and the unit that fits: a driven run
    sampled every few seconds, a duty that never exceeds 1 %, an input beyond a thin wire's."""
    column, unit = columns["time"]
    step = float(np.median(np.diff(time)))
    if step > MAX_DRIVEN_STEP_S:
        raise DiagnosisInputError(
            f"{table.path}: column {column}: samples {step:g} s apart (median) over "
            f"{time[-1]:g} s, too slow for an electrically driven wire: a time in ms declared "
            f"as {unit or 's'}? map it as time={column}:ms"
        )
    column, unit = columns[drive]
    top = float(np.max(values))
    if drive == "duty" and (unit or "%") == "%" and 0.0 < top <= 1.0:
        raise DiagnosisInputError(
            f"{table.path}: column {column}: the duty never exceeds {top:g} %: a 0-1 "
            f"fraction declared as %? map it as duty={column}:1"
        )
    if drive in MAX_INPUT and top > MAX_INPUT[drive]:
        small = "mA" if drive == "current" else "mV"
        raise DiagnosisInputError(
            f"{table.path}: column {column}: a {drive} of {top:g} "
            f"{units.default_unit(drive)}, beyond a thin SMA wire's: {small} declared as "
            f"{unit or units.default_unit(drive)}? map it as {drive}={column}:{small}"
        )


def _under_tension(table: _Table, column: str, load: np.ndarray) -> None:
    if not np.all(load > 0):
        row = int(np.argmax(~(load > 0)))
        raise DiagnosisInputError(
            f"{table.where(table.rows[row][0], table.header.index(column))}: stress "
            f"{load[row]:.4g} Pa: a thermal cycle needs the wire under tension in every row"
        )


def _wandering(load: np.ndarray, notes: list[str]) -> bool:
    """Whether the frame let the stress wander beyond STRESS_TOLERANCE of its mean (the model
    then takes it row by row)."""
    mean = float(np.mean(load))
    if np.max(np.abs(load - mean)) <= STRESS_TOLERANCE * mean:
        return False
    notes.append(
        f"stress {np.min(load) / 1e6:.4g}-{np.max(load) / 1e6:.4g} MPa (mean "
        f"{mean / 1e6:.4g}, sd {np.std(load) / 1e6:.3g}): the model takes it row by row"
    )
    return True


def _thermal_cycle(
    table: _Table, columns: Columns, name: str, cross_section_m2: float, gauge_length_m: float
) -> TimeSeriesRun:
    path = table.path
    _restrict(
        columns,
        ("time", "temperature", "strain", "displacement", "extension", *LOAD_QUANTITIES),
        "a thermal cycle",
        path,
    )
    if "strain" in columns and "extension" in columns:
        raise DiagnosisInputError(
            f"{path}: strain and extension both mapped: map one (an extension becomes strain "
            "over the gauge length, the --model wire's length)"
        )
    outputs, keep, notes = _outputs(table, columns, ("strain", "displacement", "extension"))
    if not outputs:
        raise DiagnosisInputError(
            f"{path}: no output column mapped: a thermal cycle needs strain=<column>[:unit], "
            f"extension=<column>[:unit] or displacement=<column>[:unit] in --columns"
        )
    if "extension" in outputs:
        outputs["strain"] = outputs.pop("extension") / gauge_length_m
        notes.append(
            f"strain from the extension column over a gauge length of {gauge_length_m:.4g} m"
        )
    loads = [q for q in LOAD_QUANTITIES if q in columns]
    if len(loads) != 1:
        raise DiagnosisInputError(
            f"{path}: a thermal cycle needs exactly one load column "
            f"(stress=<column>[:unit] or load_force=<column>[:unit]); mapped: "
            f"{', '.join(loads) or 'none'}"
        )
    load = _numbers(table, loads[0], *columns[loads[0]])
    if loads[0] != "stress":
        load = load / cross_section_m2
        notes.append(
            f"stress from the {loads[0]} column over a wire cross-section of "
            f"{cross_section_m2:.4g} m2"
        )
    _under_tension(table, columns[loads[0]][0], load)
    temperature = _numbers(table, "temperature", *columns["temperature"])
    if "time" in columns:
        time = _untied(_numbers(table, "time", *columns["time"]), notes)
        _check_time(table, time, "time")
    else:
        # the path's own parameter: a row that does not move the temperature on (a plateau of a
        # digitised curve) adds nothing a quasi-static model could follow
        still = np.r_[False, np.diff(temperature) == 0.0] & keep
        if still.any():
            keep = keep & ~still
            notes.append(
                f"{int(still.sum())} row(s) at the temperature of the row before dropped: "
                "without a time column, the path is the temperature's"
            )
        time = np.concatenate(([0.0], np.cumsum(np.abs(np.diff(temperature)))))
        notes.append("no time column: time is the cumulative temperature change at 1 degC per s")
    time, outputs = _kept(time, outputs, keep)
    temperature, load = temperature[keep], load[keep]
    order = _from_coldest(temperature, load, notes)
    if order is not None:
        time = _rotated_time(time, order)
        temperature, load = temperature[order], load[order]
        outputs = {k: v[order] - v[order][0] for k, v in outputs.items()}
    wandering = _wandering(load, notes)
    require_span(str(path), time, "thermal_cycle")
    return TimeSeriesRun(
        name=name,
        source=str(path),
        kind="thermal_cycle",
        time=time,
        drive="temperature",
        drive_values=temperature,
        outputs=outputs,
        stress_pa=float(load[0]) if wandering else float(np.mean(load)),
        stress_values=load if wandering else None,
        notes=tuple(notes),
    )


def _from_coldest(temperature: np.ndarray, load: np.ndarray, notes: list[str]) -> np.ndarray | None:
    """The rows to replay of a thermal cycle, in order, or None for all as they come.

    Rows where a frame was still loading the wire (before the load first comes within
    STRESS_TOLERANCE of where it ends) are left out. A cycle that then starts warm and closes
    (it ends within CLOSED_C of its start) is read from its coldest row, where the wire is
    martensite as the replay starts it: the rows before that follow the last one, the first
    left out (the cycle closes on it)."""
    n = temperature.size
    held = np.abs(load - load[-1]) <= STRESS_TOLERANCE * load[-1]
    start = int(np.argmax(held))
    if start:
        notes.append(
            f"the first {start} row(s) load the wire ({load[0] / 1e6:.4g} -> "
            f"{load[start] / 1e6:.4g} MPa at {temperature[0]:.4g} degC): left out, the cycle "
            "starts once the load is held"
        )
    coldest = start + int(np.argmin(temperature[start:]))
    if (
        temperature[start] - temperature[coldest] <= CLOSED_C
        or abs(temperature[-1] - temperature[start]) > CLOSED_C
    ):
        return np.arange(start, n) if start else None
    notes.append(
        f"the cycle starts warm ({temperature[start]:.4g} degC) and closes: read from its "
        f"coldest row ({temperature[coldest]:.4g} degC), the rows before it after the last"
    )
    return np.r_[np.arange(coldest, n), np.arange(start + 1, coldest + 1)]


def _rotated_time(time: np.ndarray, order: np.ndarray) -> np.ndarray:
    """Times of the rotated rows: each row keeps its step from the row before it (the first
    row's after the last, which closes the cycle on it)."""
    return np.r_[0.0, np.cumsum(np.diff(time)[order[1:] - 1])]


def _features(table: _Table, columns: Columns, name: str) -> FeatureRun:
    path = table.path
    _restrict(columns, (*FEATURE_QUANTITIES, "current", "name"), "a feature table", path)
    figures = [q for q in FIGURE_UNITS if q in columns]
    if not figures:
        raise DiagnosisInputError(
            f"{path}: no figure column mapped: a feature table needs one of "
            f"{', '.join(FIGURE_UNITS)}"
        )
    if "pulse_length" not in columns and "protocol" not in columns:
        raise DiagnosisInputError(
            f"{path}: a feature table needs what each test did: map pulse_length "
            f"(a current pulse) or protocol (a closed-loop run)"
        )
    if len(table.rows) < MIN_TESTS:
        raise DiagnosisInputError(
            f"{path}: only {len(table.rows)} test row, too few to compare "
            f"(a feature table needs at least {MIN_TESTS})"
        )
    values: dict[str, list[str] | np.ndarray] = {
        q: (
            _texts(table, q, c)
            if q in units.STRING_QUANTITIES
            else _numbers(table, q, c, u, blanks=q in FIGURE_UNITS)
        )
        for q, (c, u) in columns.items()
    }
    tests = []
    for k, (number, _) in enumerate(table.rows):
        conditions = {CONDITIONS[q]: _item(values[q][k]) for q in CONDITIONS if q in values}
        given = {q: x for q in figures if math.isfinite(x := float(values[q][k]))}
        if not given:
            raise DiagnosisInputError(
                f"{path}, row {number}: no figure given (every figure cell is empty)"
            )
        tests.append(
            FeatureTest(
                name=(values["name"][k] if "name" in values else "") or f"row {number}",
                conditions=conditions,
                figures=given,
            )
        )
    return FeatureRun(name=name, source=str(path), tests=tuple(tests), notes=table.notes)


def _item(value) -> float | str:
    return value if isinstance(value, str) else float(value)
