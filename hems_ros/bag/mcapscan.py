"""A forward scan over the records of one MCAP file that survives unfinished files.

The scan walks the data section record by record and never needs the summary, so it reads a
bag whose writer was killed (no summary, no footer) or whose file was cut anywhere: it stops
at the first incomplete record and, if that record is a chunk, decompresses what is there
and keeps every complete message in it. A chunk whose CRC does not match is skipped and
named in the report. A file without the MCAP magic or header record is rejected at once.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import lz4.frame
import zstandard

MAGIC = b"\x89MCAP0\r\n"
OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK = (
    0x01,
    0x02,
    0x03,
    0x04,
    0x05,
    0x06,
)
OP_DATA_END = 0x0F
_RECORD = struct.Struct("<BQ")
_MESSAGE = struct.Struct("<HIQQ")
_CHUNK = struct.Struct("<QQQI")
_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
RECORD_HEADER = _RECORD.size
MESSAGE_HEADER = _MESSAGE.size

#: One message as stored: (channel id, log time ns, publish time ns, serialized bytes).
RawRecord = tuple[int, int, int, bytes]


class BagFormatError(ValueError):
    """The file is not an MCAP file, or its header is damaged."""


@dataclass(frozen=True)
class Schema:
    id: int
    name: str
    encoding: str
    data: bytes


@dataclass(frozen=True)
class Channel:
    id: int
    schema_id: int
    topic: str
    message_encoding: str
    metadata: dict[str, str]


@dataclass
class ScanReport:
    """How far the scan got: complete files read to their footer, others up to ``stopped_at``."""

    file: Path
    size: int
    complete: bool = False
    messages: int = 0
    chunks: int = 0
    stopped_at: int | None = None
    reason: str = ""
    last_log_time_ns: int | None = None
    skipped: list[str] = field(default_factory=list)

    def describe(self) -> str:
        if self.complete and not self.skipped:
            return f"{self.file.name}: complete, {self.messages} messages in {self.chunks} chunks"
        text = (
            f"{self.file.name}: recovered {self.messages} messages from {self.chunks} chunks; "
            f"stopped at byte {self.stopped_at} of {self.size}: {self.reason}"
        )
        if self.last_log_time_ns is not None:
            text += f" (last message logged at {self.last_log_time_ns * 1e-9:.6f} s)"
        if self.skipped:
            text += "; skipped: " + "; ".join(self.skipped)
        return text


def _string(buf: bytes, pos: int) -> tuple[str, int]:
    (length,) = _U32.unpack_from(buf, pos)
    try:
        return str(buf[pos + 4 : pos + 4 + length], "utf-8"), pos + 4 + length
    except UnicodeDecodeError:
        raise BagFormatError(f"the string at byte {pos} is not UTF-8 (a damaged record)") from None


def _schema(buf: bytes, pos: int) -> Schema:
    (schema_id,) = _U16.unpack_from(buf, pos)
    name, pos = _string(buf, pos + 2)
    encoding, pos = _string(buf, pos)
    (length,) = _U32.unpack_from(buf, pos)
    return Schema(schema_id, name, encoding, bytes(buf[pos + 4 : pos + 4 + length]))


def _channel(buf: bytes, pos: int) -> Channel:
    channel_id, schema_id = struct.unpack_from("<HH", buf, pos)
    topic, pos = _string(buf, pos + 4)
    encoding, pos = _string(buf, pos)
    (length,) = _U32.unpack_from(buf, pos)
    pos += 4
    end = pos + length
    metadata = {}
    while pos < end:
        key, pos = _string(buf, pos)
        metadata[key], pos = _string(buf, pos)
    return Channel(channel_id, schema_id, topic, encoding, metadata)


# Writers cut chunks at a few MiB; a size field beyond this is damage, not data.
_MAX_CHUNK_BYTES = 1 << 30


def _decompress(compression: str, data: bytes, size: int, partial: bool) -> bytes:
    if compression == "":
        return data
    if compression == "zstd":
        if partial:
            return zstandard.ZstdDecompressor().decompressobj().decompress(data)
        return zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
    if compression == "lz4":
        if partial:
            return lz4.frame.LZ4FrameDecompressor().decompress(data)
        return lz4.frame.decompress(data)
    raise BagFormatError(f"unsupported chunk compression {compression!r}")


class McapScan:
    """Scan one MCAP file; iterate ``messages()`` once, then read ``report``.

    ``accept(channel)`` decides per channel, when it first appears, whether its messages
    are yielded; ``schemas`` and ``channels`` fill up as the scan meets them.
    """

    def __init__(self, path: str | Path, accept: Callable[[Channel], bool] | None = None) -> None:
        self.path = Path(path)
        self._buf = self.path.read_bytes()
        self._accept = accept or (lambda channel: True)
        self._wanted: dict[int, bool] = {}
        self.schemas: dict[int, Schema] = {}
        self.channels: dict[int, Channel] = {}
        self.report = ScanReport(self.path, len(self._buf))
        self._check_header()

    def _check_header(self) -> None:
        buf = self._buf
        if len(buf) < len(MAGIC) or buf[: len(MAGIC)] != MAGIC:
            raise BagFormatError(f"{self.path}: not an MCAP file (bad magic {bytes(buf[:8])!r})")
        if len(buf) < len(MAGIC) + RECORD_HEADER:
            raise BagFormatError(
                f"{self.path}: MCAP header record missing (file is {len(buf)} bytes)"
            )
        opcode, length = _RECORD.unpack_from(buf, len(MAGIC))
        if opcode != OP_HEADER or len(MAGIC) + RECORD_HEADER + length > len(buf):
            raise BagFormatError(
                f"{self.path}: bad MCAP header record (opcode {opcode:#04x}, length {length})"
            )

    def _stop(self, position: int, reason: str) -> None:
        self.report.stopped_at = position
        self.report.reason = reason

    def _register(self, opcode: int, buf: bytes, body: int) -> None:
        if opcode == OP_SCHEMA:
            schema = _schema(buf, body)
            self.schemas[schema.id] = schema
        else:
            channel = _channel(buf, body)
            if channel.id not in self.channels:
                self.channels[channel.id] = channel
                self._wanted[channel.id] = self._accept(channel)

    def _records(self, buf: bytes, pos: int, end: int) -> Iterator[RawRecord]:
        """Messages of a record run (a chunk's content); stops quietly at an incomplete tail."""
        unpack_record, unpack_message, wanted = (
            _RECORD.unpack_from,
            _MESSAGE.unpack_from,
            self._wanted,
        )
        report = self.report
        while pos + RECORD_HEADER <= end:
            opcode, length = unpack_record(buf, pos)
            body = pos + RECORD_HEADER
            nxt = body + length
            if nxt > end:
                return
            if opcode == OP_MESSAGE:
                channel_id, _, log_time, publish_time = unpack_message(buf, body)
                report.messages += 1
                report.last_log_time_ns = log_time
                if wanted.get(channel_id):
                    yield channel_id, log_time, publish_time, buf[body + MESSAGE_HEADER : nxt]
            elif opcode in (OP_SCHEMA, OP_CHANNEL):
                self._register(opcode, buf, body)
            pos = nxt

    def _chunk(self, buf: bytes, body: int, end: int, record_start: int) -> Iterator[RawRecord]:
        size = len(buf)
        if body + _CHUNK.size + 4 > size:
            self._stop(record_start, "file ends inside a chunk header")
            return
        _, _, uncompressed_size, crc = _CHUNK.unpack_from(buf, body)
        if uncompressed_size > _MAX_CHUNK_BYTES:
            raise BagFormatError(
                f"chunk declares {uncompressed_size} bytes uncompressed "
                f"(more than {_MAX_CHUNK_BYTES}); the size field is damaged"
            )
        compression, pos = _string(buf, body + _CHUNK.size)
        if pos + 8 > size:
            self._stop(record_start, "file ends inside a chunk header")
            return
        (records_length,) = _U64.unpack_from(buf, pos)
        pos += 8
        partial = end > size
        data = _decompress(
            compression, buf[pos : min(pos + records_length, size)], uncompressed_size, partial
        )
        if partial:
            before = self.report.messages
            yield from self._records(data, 0, len(data))
            self._stop(
                record_start,
                f"file ends inside a chunk ({size - record_start} of "
                f"{end - record_start} bytes present); {self.report.messages - before} "
                f"complete messages recovered from it",
            )
            return
        if crc and zlib.crc32(data) != crc:
            self.report.skipped.append(f"chunk at byte {record_start} fails its CRC")
            return
        self.report.chunks += 1
        yield from self._records(data, 0, len(data))

    def messages(self) -> Iterator[RawRecord]:
        buf, size = self._buf, len(self._buf)
        pos = len(MAGIC)
        while True:
            if pos + RECORD_HEADER > size:
                self._stop(
                    pos,
                    "file ends without data end record (writer did not finish)"
                    if pos == size
                    else "file ends inside a record header",
                )
                return
            opcode, length = _RECORD.unpack_from(buf, pos)
            body = pos + RECORD_HEADER
            end = body + length
            if opcode == OP_CHUNK:
                try:
                    yield from self._chunk(buf, body, end, pos)
                except (
                    zstandard.ZstdError,
                    RuntimeError,
                    BagFormatError,
                    struct.error,
                    MemoryError,
                    OverflowError,
                ) as error:
                    if end > size:
                        self._stop(
                            pos, f"file ends inside a chunk that cannot be decompressed ({error})"
                        )
                        return
                    self.report.skipped.append(f"chunk at byte {pos}: {error}")
                if end > size:
                    return
            elif end > size:
                self._stop(pos, f"file ends inside a record (opcode {opcode:#04x})")
                return
            elif opcode == OP_MESSAGE:
                yield from self._records(buf, pos, end)
            elif opcode in (OP_SCHEMA, OP_CHANNEL):
                self._register(opcode, buf, body)
            elif opcode in (OP_DATA_END, OP_FOOTER):
                self.report.complete = buf.endswith(MAGIC) and size >= 2 * len(MAGIC)
                if not self.report.complete:
                    self._stop(end, "summary or footer is incomplete")
                return
            pos = end
