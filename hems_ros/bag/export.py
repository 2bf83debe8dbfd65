"""One CSV file per topic of a bag, for spreadsheets, MATLAB and plotting tools without
MCAP support.

Columns of each file, one row per message in log-time order:

- ``time_s``: log time in seconds since the start of the bag (the axis ``hems`` plots use);
- ``log_time_ns``: the absolute log time, an integer, exact;
- ``stamp_s``: ``header.stamp`` in seconds, for messages with a header (publisher's clock);
- every field under its dotted name (``header.stamp.sec``, ``wire_force``, ...), in SI units
  as on the topic. Numbers are written in their shortest exact form, so a float read back is
  the recorded value; booleans as 1 and 0. An array field of the same length in every message
  of the topic becomes one column per element (``position[0]``, ...); one whose length varies
  is one cell per message with the elements joined by ``;``; a sequence of nested messages
  (``/diagnostics``) is one cell of JSON. Nothing of the message is left out.
"""

from __future__ import annotations

import csv
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from hems_ros.bag.reader import Bag, TopicData, load_bag
from hems_ros.bag.selection import TopicSelection

SEQUENCE_SEPARATOR = ";"


@dataclass(frozen=True)
class ExportedTopic:
    topic: str
    path: Path
    rows: int
    columns: int


def csv_name(topic: str) -> str:
    """File name of a topic's CSV: ``/hems/index/encoder`` -> ``hems.index.encoder.csv``."""
    return topic.strip("/").replace("/", ".") + ".csv"


def _number_cells(values: np.ndarray) -> list[str]:
    if values.dtype == bool:
        return ["1" if v else "0" for v in values.tolist()]
    return [
        repr(v) for v in values.tolist()
    ]  # Python float repr: shortest string that reads back exactly


def _cell(value) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "1" if value else "0"
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    return str(value)


def _sequence_cells(values: np.ndarray) -> list[str]:
    # decided per column, so an empty sequence of nested messages still reads as JSON ("[]")
    if any(isinstance(item, dict) for element in values for item in element):
        return [json.dumps([_jsonable(item) for item in element]) for element in values]
    return [SEQUENCE_SEPARATOR.join(_cell(item) for item in element) for element in values]


def _jsonable(value):
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (bytes, bytearray)):
        return list(value)
    if isinstance(value, np.generic):
        return value.item()
    return value


def topic_columns(data: TopicData) -> list[tuple[str, list[str]]]:
    """(column name, cells) of every column of ``data``'s CSV, in file order."""
    # divided, not multiplied by 1e-9: the nearest double to each exact time, so it prints short
    columns = [
        ("time_s", _number_cells((data.log_time_ns - data.start_ns) / 1e9)),
        ("log_time_ns", _number_cells(data.log_time_ns)),
    ]
    if "header.stamp.sec" in data.fields and "header.stamp.nanosec" in data.fields:
        columns.append(("stamp_s", _number_cells(data.stamp)))
    for name, values in data.fields.items():
        if values.dtype == object:
            columns.append((name, _sequence_cells(values)))
        elif values.ndim == 2:
            columns += [
                (f"{name}[{k}]", _number_cells(values[:, k])) for k in range(values.shape[1])
            ]
        elif values.dtype.kind in "US":
            columns.append((name, [str(v) for v in values.tolist()]))
        else:
            columns.append((name, _number_cells(values)))
    return columns


def write_topic_csv(data: TopicData, path: str | os.PathLike) -> ExportedTopic:
    columns = topic_columns(data)
    path = Path(path)
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow([name for name, _ in columns])
        writer.writerows(zip(*(cells for _, cells in columns)))
    return ExportedTopic(data.topic, path, len(data), len(columns))


def export_csv(
    bag: str | os.PathLike | Bag,
    out_dir: str | os.PathLike,
    topics: Iterable[str] | None = None,
    regex: str | None = None,
    progress: Callable[[ExportedTopic], None] | None = None,
) -> list[ExportedTopic]:
    """Write ``out_dir/<topic>.csv`` for every selected topic with messages (see the module doc).

    ``bag`` is a bag folder, an ``.mcap`` file or a :class:`Bag` already loaded; ``topics`` and
    ``regex`` select as :func:`hems_ros.bag.load_bag` does.
    """
    loaded = bag if isinstance(bag, Bag) else load_bag(bag, topics=topics, regex=regex)
    selection = TopicSelection.of(topics, regex)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for topic in sorted(t for t in loaded.topics if selection.matches(t)):
        entry = write_topic_csv(loaded.topics[topic], out / csv_name(topic))
        written.append(entry)
        if progress is not None:
            progress(entry)
    return written
