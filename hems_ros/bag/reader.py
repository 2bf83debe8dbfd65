"""Read bags into per-topic numpy columns, or as raw serialized messages.

``load_bag`` decodes every selected topic with decoders generated from the definitions stored
in the bag (no ROS installation needed) and returns one :class:`TopicData` per topic: the log
times and one numpy array per leaf field (``force``, ``header.stamp.sec``...). Unfinished or
cut files are read as far as they go (:class:`~hems_ros.bag.mcapscan.ScanReport` says how
far); a topic whose schema cannot be decoded is skipped with a warning naming it.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from hems_ros.bag import columns
from hems_ros.bag.mcapscan import BagFormatError, Channel, McapScan, ScanReport, Schema
from hems_ros.bag.selection import TopicSelection
from hems_ros.codec import cdr, msgdefs

__all__ = [
    "Bag",
    "BagFormatError",
    "BagInfo",
    "BagWarning",
    "RawMessage",
    "TopicData",
    "bag_files",
    "bag_info",
    "iter_messages",
    "load_bag",
]


class BagWarning(UserWarning):
    """Part of a bag could not be read (unknown schema, undecodable messages)."""


@dataclass(frozen=True)
class RawMessage:
    topic: str
    type: str
    log_time_ns: int
    publish_time_ns: int
    data: bytes
    offered_qos_profiles: str
    definition: str = ""  # the schema stored with the message, as the writer knew its type


@dataclass
class TopicData:
    """One topic's messages as columns; ``data["force"]`` is a numpy array."""

    topic: str
    type: str
    log_time_ns: np.ndarray
    publish_time_ns: np.ndarray
    fields: dict[str, np.ndarray]
    start_ns: int = 0

    def __len__(self) -> int:
        return len(self.log_time_ns)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.fields[name]

    @property
    def time(self) -> np.ndarray:
        """Log time in seconds since the start of the bag."""
        return (self.log_time_ns - self.start_ns) * 1e-9

    @property
    def stamp(self) -> np.ndarray:
        """``header.stamp`` in seconds (the publisher's clock)."""
        return self.fields["header.stamp.sec"] + self.fields["header.stamp.nanosec"] * 1e-9

    def records(self) -> np.ndarray:
        """A numpy structured array: ``time`` plus every scalar and string field."""
        names = [n for n, a in self.fields.items() if a.dtype != object]
        dtype = [("time", np.float64)] + [(n, self.fields[n].dtype) for n in names]
        out = np.empty(len(self), dtype=dtype)
        out["time"] = self.time
        for name in names:
            out[name] = self.fields[name]
        return out


@dataclass
class Bag:
    path: Path
    topics: dict[str, TopicData]
    reports: list[ScanReport]
    warnings: list[str] = field(default_factory=list)
    start_ns: int = 0
    end_ns: int = 0

    def __getitem__(self, topic: str) -> TopicData:
        return self.topics[topic]

    def __contains__(self, topic: str) -> bool:
        return topic in self.topics

    @property
    def complete(self) -> bool:
        return all(r.complete and not r.skipped for r in self.reports)


@dataclass
class TopicCount:
    type: str
    count: int = 0
    first_ns: int | None = None
    last_ns: int | None = None


@dataclass
class BagInfo:
    path: Path
    files: list[Path]
    topics: dict[str, TopicCount]
    reports: list[ScanReport]
    warnings: list[str]

    @property
    def message_count(self) -> int:
        return sum(t.count for t in self.topics.values())

    @property
    def start_ns(self) -> int:
        return min((t.first_ns for t in self.topics.values() if t.first_ns is not None), default=0)

    @property
    def end_ns(self) -> int:
        return max((t.last_ns for t in self.topics.values() if t.last_ns is not None), default=0)


def bag_files(path: str | os.PathLike) -> list[Path]:
    """The MCAP files of a bag folder (in ``metadata.yaml`` order) or the file itself."""
    path = Path(path)
    if path.is_file():
        return [path]
    if not path.is_dir():
        raise FileNotFoundError(f"no bag at {path}")
    metadata = path / "metadata.yaml"
    if metadata.is_file():
        try:
            info = yaml.safe_load(metadata.read_text(encoding="utf-8"))[
                "rosbag2_bagfile_information"
            ]
            files = [path / Path(p).name for p in info["relative_file_paths"]]
            if all(f.is_file() for f in files):
                return files
        except (yaml.YAMLError, KeyError, TypeError):
            pass
    files = sorted(path.glob("*.mcap"), key=lambda p: (len(p.name), p.name))
    if not files:
        raise FileNotFoundError(f"no .mcap file in {path}")
    return files


def _warn(warnings_out: list[str], text: str) -> None:
    warnings_out.append(text)
    warnings.warn(text, BagWarning, stacklevel=3)


class _Decoders:
    """Decoders per schema, built once; a schema that cannot be decoded is reported per topic."""

    def __init__(self, warnings_out: list[str]) -> None:
        self._built: dict[int, cdr.Decoder | str] = {}
        self._warned: set[str] = set()
        self._warnings = warnings_out

    def for_channel(self, channel: Channel, schemas: dict[int, Schema]) -> cdr.Decoder | None:
        schema = schemas.get(channel.schema_id)
        if schema is None:
            problem = f"schema id {channel.schema_id} is not in the file"
        elif channel.message_encoding != "cdr" or schema.encoding != "ros2msg":
            problem = (
                f"schema {schema.name!r} has encoding {schema.encoding!r} "
                f"(messages {channel.message_encoding!r}); only ros2msg/cdr is read"
            )
        else:
            built = self._built.get(schema.id)
            if built is None:
                try:
                    types = msgdefs.parse_full_definition(schema.name, schema.data.decode("utf-8"))
                    built = cdr.build_decoder(msgdefs.full_name(schema.name), types)
                except (msgdefs.DefinitionError, UnicodeDecodeError) as error:
                    built = str(error)
                self._built[schema.id] = built
            if isinstance(built, cdr.Decoder):
                return built
            problem = f"schema {schema.name!r} cannot be parsed: {built}"
        if channel.topic not in self._warned:
            self._warned.add(channel.topic)
            _warn(self._warnings, f"skipping topic {channel.topic}: unknown schema ({problem})")
        return None


def load_bag(
    path: str | os.PathLike, topics: Iterable[str] | None = None, regex: str | None = None
) -> Bag:
    """Decode a bag (folder or ``.mcap`` file) into per-topic numpy columns.

    ``topics`` (exact names) and ``regex`` select topics; both empty takes every topic.
    Raises :class:`BagFormatError` for a file that is not MCAP or has a bad header.
    """
    selection = TopicSelection.of(topics, regex)
    warnings_out: list[str] = []
    decoders = _Decoders(warnings_out)
    collected: dict[str, tuple[cdr.Decoder, list[bytes], list[int], list[int]]] = {}
    reports = []
    for file in bag_files(path):
        scan = McapScan(file, lambda channel: selection.matches(channel.topic))
        sinks: dict[int, tuple[list[bytes], list[int], list[int]] | None] = {}
        for channel_id, log_time, publish_time, payload in scan.messages():
            if channel_id not in sinks:
                channel = scan.channels[channel_id]
                decoder = decoders.for_channel(channel, scan.schemas)
                sink = None
                if decoder is not None:
                    entry = collected.setdefault(channel.topic, (decoder, [], [], []))
                    sink = entry[1:]
                sinks[channel_id] = sink
            sink = sinks[channel_id]
            if sink is not None:
                sink[0].append(payload)
                sink[1].append(log_time)
                sink[2].append(publish_time)
        reports.append(scan.report)
    start = min((e[2][0] for e in collected.values() if e[2]), default=0)
    end = max((max(e[2]) for e in collected.values() if e[2]), default=0)
    data: dict[str, TopicData] = {}
    for topic, (decoder, datas, log_times, publish_times) in collected.items():
        fields, index, errors = columns.decode_columns(decoder, datas)
        if errors:
            _warn(
                warnings_out,
                f"{topic}: {len(errors)} messages could not be decoded (first: {errors[0]})",
            )
        data[topic] = TopicData(
            topic,
            decoder.type_name,
            np.array(log_times, dtype=np.int64)[index],
            np.array(publish_times, dtype=np.int64)[index],
            fields,
            start,
        )
    return Bag(Path(path), data, reports, warnings_out, start, end)


def iter_messages(
    path: str | os.PathLike,
    topics: Iterable[str] | None = None,
    regex: str | None = None,
    reports: list[ScanReport] | None = None,
) -> Iterator[RawMessage]:
    """The selected messages in file order, serialized as stored (for replay and copying).

    Each file's scan report is appended to ``reports`` when given.
    """
    selection = TopicSelection.of(topics, regex)
    for file in bag_files(path):
        scan = McapScan(file, lambda channel: selection.matches(channel.topic))
        for channel_id, log_time, publish_time, data in scan.messages():
            channel = scan.channels[channel_id]
            schema = scan.schemas.get(channel.schema_id)
            yield RawMessage(
                channel.topic,
                schema.name if schema else "",
                log_time,
                publish_time,
                data,
                channel.metadata.get("offered_qos_profiles", ""),
                schema.data.decode(errors="replace") if schema else "",
            )
        if reports is not None:
            reports.append(scan.report)


def bag_info(path: str | os.PathLike) -> BagInfo:
    """Message counts and time range per topic, read by scanning (works on unfinished bags)."""
    files = bag_files(path)
    topics: dict[str, TopicCount] = {}
    reports: list[ScanReport] = []
    warnings_out: list[str] = []
    decoders = _Decoders(warnings_out)
    for file in files:
        scan = McapScan(file)
        counts: dict[int, TopicCount] = {}
        for channel_id, log_time, _, _ in scan.messages():
            entry = counts.get(channel_id)
            if entry is None:
                channel = scan.channels[channel_id]
                schema = scan.schemas.get(channel.schema_id)
                entry = counts[channel_id] = topics.setdefault(
                    channel.topic, TopicCount(schema.name if schema else "?")
                )
            entry.count += 1
            entry.first_ns = log_time if entry.first_ns is None else min(entry.first_ns, log_time)
            entry.last_ns = log_time if entry.last_ns is None else max(entry.last_ns, log_time)
        for channel in scan.channels.values():
            decoder = decoders.for_channel(channel, scan.schemas)
            topics.setdefault(channel.topic, TopicCount(decoder.type_name if decoder else "?"))
        reports.append(scan.report)
    return BagInfo(Path(path), files, topics, reports, warnings_out)
