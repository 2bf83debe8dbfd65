"""MCAP bags in the rosbag2 layout: ``<folder>/<folder>_0.mcap`` plus ``metadata.yaml``.

Messages are stored as the serialized CDR bytes they arrived as. The file is chunked and
compressed; every finished chunk is handed to the operating system at once, so a writer
killed without warning leaves all finished chunks readable (``flush`` finishes the open
chunk on demand, which the recorder does on a timer). ``finish`` writes the summary
(schemas, channels, chunk indexes, statistics), the footer, and ``metadata.yaml`` as
``ros2 bag info`` (rosbag2 metadata version 9) and ``rosbags`` read it.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

import yaml
from mcap.data_stream import RecordBuilder
from mcap.writer import CompressionType, Writer

from hems_ros.codec import msgdefs

if TYPE_CHECKING:
    from hems_ros.bag.reader import RawMessage

METADATA_VERSION = 9
PROFILE = "ros2"
LIBRARY = "hems_ros.bag"
DEFAULT_CHUNK_SIZE = 256 * 1024
COMPRESSIONS = {
    "zstd": CompressionType.ZSTD,
    "lz4": CompressionType.LZ4,
    "none": CompressionType.NONE,
}
INFINITE = {"sec": 9223372036, "nsec": 854775807}  # rosbag2's spelling of an unset duration
INFINITE_NS = INFINITE["sec"] * 1_000_000_000 + INFINITE["nsec"]


class _PlainDumper(yaml.SafeDumper):
    """No anchors or aliases: rosbag2's metadata reader expects plain mappings."""

    def ignore_aliases(self, data: object) -> bool:
        return True


def _dump(data: object) -> str:
    return yaml.dump(data, Dumper=_PlainDumper, sort_keys=False)


def offered_qos(
    reliable: bool = True, transient_local: bool = False, depth: int = 0, lease_ns: int = 0
) -> dict:
    """One offered QoS profile as rosbag2 (metadata version 9) writes it; ``lease_ns``: the
    liveliness lease, 0 for none (infinite)."""
    lease = (
        {"sec": lease_ns // 1_000_000_000, "nsec": lease_ns % 1_000_000_000}
        if 0 < lease_ns < INFINITE_NS
        else dict(INFINITE)
    )
    return {
        "history": "keep_last" if depth else "unknown",
        "depth": depth,
        "reliability": "reliable" if reliable else "best_effort",
        "durability": "transient_local" if transient_local else "volatile",
        "deadline": dict(INFINITE),
        "lifespan": dict(INFINITE),
        "liveliness": "automatic",
        "liveliness_lease_duration": lease,
        "avoid_ros_namespace_conventions": False,
    }


def offered_lease_ns(profile: dict) -> int:
    """The liveliness lease an offered QoS profile (as :func:`offered_qos` writes it) names,
    ns; 0 when it names none, an infinite one, or one that cannot be read."""
    try:
        duration = profile["liveliness_lease_duration"]
        ns = int(duration["sec"]) * 1_000_000_000 + int(duration["nsec"])
    except (TypeError, KeyError, ValueError):
        return 0
    return ns if 0 < ns < INFINITE_NS else 0


@dataclass
class TopicRecord:
    topic: str
    type: str
    channel_id: int
    offered_qos_profiles: list[dict]
    type_description_hash: str
    count: int = 0


@dataclass
class BagSummary:
    """What a finished bag holds."""

    folder: Path
    file: Path
    counts: dict[str, int] = field(default_factory=dict)
    start_ns: int = 0
    end_ns: int = 0

    @property
    def message_count(self) -> int:
        return sum(self.counts.values())

    @property
    def duration_s(self) -> float:
        return max(0, self.end_ns - self.start_ns) * 1e-9


class _WrittenRecord:
    """A summary record kept as the bytes it will be written as.

    The mcap writer keeps one ChunkIndex per closed chunk until the file is finished, each
    with a dict of message-index offsets per channel: about 2.7 kB per chunk with the graph's
    forty topics, 10 MB over a 30-minute recording that closes a chunk every 0.5 s. Written
    out, the same index is some 450 bytes; the summary needs nothing else of it."""

    __slots__ = ("data",)

    def __init__(self, record) -> None:
        builder = RecordBuilder()
        record.write(builder)
        self.data = builder.end()

    def write(self, stream: RecordBuilder) -> None:
        stream.write(self.data)


class BagWriter:
    """Write one bag folder; use as a context manager so the file is always finished.

    ``folder`` must not exist or be empty. ``compression`` is ``zstd``, ``lz4`` or ``none``;
    a chunk is closed when it holds ``chunk_size`` bytes or when ``flush`` is called.
    """

    def __init__(
        self,
        folder: str | os.PathLike,
        compression: str = "zstd",
        chunk_size: int = DEFAULT_CHUNK_SIZE,
    ) -> None:
        if compression not in COMPRESSIONS:
            raise ValueError(
                f"compression must be one of {', '.join(COMPRESSIONS)}, not {compression!r}"
            )
        self.folder = Path(folder)
        if self.folder.exists() and (not self.folder.is_dir() or any(self.folder.iterdir())):
            raise FileExistsError(f"{self.folder} exists and is not an empty folder")
        self.folder.mkdir(parents=True, exist_ok=True)
        self.file = self.folder / f"{self.folder.name}_0.mcap"
        self._stream = open(self.file, "xb")
        self._mcap = Writer(
            self._stream, chunk_size=chunk_size, compression=COMPRESSIONS[compression]
        )
        self._mcap.start(profile=PROFILE, library=LIBRARY)
        self._chunk_indexes: list = vars(self._mcap)["_Writer__chunk_indices"]  # see _WrittenRecord
        self._compacted = 0
        self._schemas: dict[str, int] = {}
        self._topics: dict[str, TopicRecord] = {}
        self._by_channel: dict[int, TopicRecord] = {}
        self._start_ns: int | None = None
        self._end_ns = 0
        self._finished: BagSummary | None = None

    @property
    def topics(self) -> dict[str, TopicRecord]:
        return self._topics

    def add_topic(
        self,
        topic: str,
        msg_type: str,
        offered_qos_profiles: list[dict] | None = None,
        definition: str | None = None,
    ) -> int:
        """Register ``topic`` of ``msg_type`` (``pkg/msg/Type``); returns its channel id.

        The full definition comes from the installed ``.msg`` files unless given.
        """
        if topic in self._topics:
            return self._topics[topic].channel_id
        msg_type = msgdefs.full_name(msg_type)
        if msg_type not in self._schemas:
            text = msgdefs.full_definition(msg_type) if definition is None else definition
            self._schemas[msg_type] = self._mcap.register_schema(msg_type, "ros2msg", text.encode())
        profiles = list(offered_qos_profiles or [])
        channel_id = self._mcap.register_channel(
            topic,
            "cdr",
            self._schemas[msg_type],
            metadata={"offered_qos_profiles": _dump(profiles).strip() if profiles else ""},
        )
        record = TopicRecord(topic, msg_type, channel_id, profiles, msgdefs.type_hash(msg_type))
        self._topics[topic] = record
        self._by_channel[channel_id] = record
        return channel_id

    def write(
        self, channel_id: int, log_time_ns: int, data: bytes, publish_time_ns: int | None = None
    ) -> None:
        """Append one serialized message (CDR bytes with encapsulation header) as is."""
        record = self._by_channel[channel_id]
        self._mcap.add_message(
            channel_id,
            log_time_ns,
            data,
            log_time_ns if publish_time_ns is None else publish_time_ns,
            record.count,
        )
        record.count += 1
        if len(self._chunk_indexes) > self._compacted:
            self._compact_chunk_indexes()
        if self._start_ns is None or log_time_ns < self._start_ns:
            self._start_ns = log_time_ns
        if log_time_ns > self._end_ns:
            self._end_ns = log_time_ns

    def write_copy(self, message: RawMessage, log_time_ns: int | None = None) -> None:
        """Append ``message`` read from another bag (``iter_messages``) on its topic, with the
        schema and offered QoS it was stored with, so that a bag recorded with an older
        definition of a type stays decodable; ``log_time_ns`` replaces its log time."""
        if message.topic not in self._topics:
            self.add_topic(
                message.topic,
                message.type,
                yaml.safe_load(message.offered_qos_profiles) or [],
                message.definition or None,
            )
        self.write(
            self._topics[message.topic].channel_id,
            message.log_time_ns if log_time_ns is None else log_time_ns,
            message.data,
            message.publish_time_ns,
        )

    def flush(self) -> None:
        """Close the open chunk and hand everything written so far to the operating system."""
        if self._finished is None:
            self._mcap.flush()
            self._compact_chunk_indexes()

    def _compact_chunk_indexes(self) -> None:
        indexes = self._chunk_indexes
        for i in range(self._compacted, len(indexes)):
            indexes[i] = _WrittenRecord(indexes[i])
        self._compacted = len(indexes)

    @property
    def finished(self) -> bool:
        return self._finished is not None

    def finish(self) -> BagSummary:
        """Write the summary, the footer and ``metadata.yaml``; idempotent."""
        if self._finished is not None:
            return self._finished
        summary = self.summary()
        self._mcap.add_metadata("rosbag2", {"serialized_metadata": _dump(self._metadata(summary))})
        self._mcap.finish()
        self._stream.close()
        self.write_metadata(summary)
        self._finished = summary
        return summary

    def summary(self) -> BagSummary:
        return BagSummary(
            self.folder,
            self.file,
            {t.topic: t.count for t in self._topics.values()},
            self._start_ns or 0,
            self._end_ns,
        )

    def write_metadata(self, summary: BagSummary) -> None:
        target = self.folder / "metadata.yaml"
        temporary = target.with_suffix(".yaml.tmp")
        temporary.write_text(
            _dump({"rosbag2_bagfile_information": self._metadata(summary)}), encoding="utf-8"
        )
        temporary.replace(target)

    def _metadata(self, summary: BagSummary) -> dict:
        duration = {"nanoseconds": max(0, summary.end_ns - summary.start_ns)}
        start = {"nanoseconds_since_epoch": summary.start_ns}
        return {
            "version": METADATA_VERSION,
            "storage_identifier": "mcap",
            "duration": duration,
            "starting_time": start,
            "message_count": summary.message_count,
            "topics_with_message_count": [
                {
                    "topic_metadata": {
                        "name": t.topic,
                        "type": t.type,
                        "serialization_format": "cdr",
                        "offered_qos_profiles": t.offered_qos_profiles,
                        "type_description_hash": t.type_description_hash,
                    },
                    "message_count": t.count,
                }
                for t in self._topics.values()
            ],
            "compression_format": "",
            "compression_mode": "",
            "relative_file_paths": [self.file.name],
            "files": [
                {
                    "path": self.file.name,
                    "starting_time": start,
                    "duration": duration,
                    "message_count": summary.message_count,
                }
            ],
            "custom_data": {"recorded_by": LIBRARY, "finished_at_unix_s": f"{time.time():.3f}"},
            "ros_distro": os.environ.get("ROS_DISTRO", "kilted"),
        }

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.finish()
