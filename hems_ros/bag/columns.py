"""Decode many messages of one type into numpy columns, vectorised where the layout repeats.

Messages of one topic nearly always share their byte layout (same ``finger`` and
``frame_id`` strings, same array lengths). The layout of one message gives every field's
offset; each other message of the same length whose string lengths and sequence counts
(read at the same offsets) are equal has, by induction over the fields, exactly the same
layout, so whole columns are cut out of a 2-D byte array at once. Messages that differ, and
types with sequences of nested messages, go through the generated per-message decoder.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np

from hems_ros.codec.cdr import HEADER_SIZE, LITTLE_ENDIAN_KINDS, SCALARS, CdrError, Column, Decoder
from hems_ros.codec.msgdefs import PRIMITIVES, Field

_U32 = struct.Struct("<I")


@dataclass(frozen=True)
class _Slot:
    kind: str  # as Column.kind: scalar, string, array; "strings" for string[]
    offset: int = 0
    width: int = 0  # string bytes without NUL, or element count of an array
    dtype: np.dtype = np.dtype("u1")  # of a scalar or array slot
    parts: tuple[tuple[int, int], ...] = ()  # (offset, width) per string of a string array


class _Unsupported(Exception):
    """A layout the vectorised path does not handle (sequences of nested messages)."""


def _align(offset: int, size: int) -> int:
    return offset + (HEADER_SIZE - offset) % size


def _layout(
    types: dict[str, list[Field]], type_name: str, data: bytes
) -> tuple[list[_Slot], list[tuple[int, int]]]:
    """Slots of every leaf field and (offset, value) of every length prefix, for one message."""
    slots: list[_Slot] = []
    checks: list[tuple[int, int]] = []

    def length_at(offset: int) -> tuple[int, int]:
        offset = _align(offset, 4)
        (value,) = _U32.unpack_from(data, offset)
        checks.append((offset, value))
        return value, offset + 4

    def string_at(offset: int) -> tuple[tuple[int, int], int]:
        length, offset = length_at(offset)
        return (offset, max(length - 1, 0)), offset + length

    def walk(name: str, offset: int) -> int:
        for field in types[name]:
            if field.array is not None and field.type not in PRIMITIVES:
                raise _Unsupported(field.name)
            if field.type == "string":
                if field.array is None:
                    (start, width), offset = string_at(offset)
                    slots.append(_Slot("string", start, width))
                    continue
                count, offset = length_at(offset) if field.is_sequence else (field.array, offset)
                parts = []
                for _ in range(count):
                    part, offset = string_at(offset)
                    parts.append(part)
                slots.append(_Slot("strings", parts=tuple(parts)))
            elif field.type in PRIMITIVES:
                _, size, dtype = SCALARS[field.type]
                if field.array is None:
                    offset = _align(offset, size)
                    slots.append(_Slot("scalar", offset, 1, np.dtype(dtype).newbyteorder("<")))
                    offset += size
                    continue
                count, offset = length_at(offset) if field.is_sequence else (field.array, offset)
                if count:
                    offset = _align(offset, size)
                slots.append(_Slot("array", offset, count, np.dtype(dtype).newbyteorder("<")))
                offset += count * size
            else:
                offset = walk(field.type, offset)
        return offset

    if walk(type_name, HEADER_SIZE) > len(data):
        raise CdrError(f"{type_name}: message shorter than its layout")
    return slots, checks


def _cut(block: np.ndarray, offset: int, width: int) -> np.ndarray:
    return np.ascontiguousarray(block[:, offset : offset + width])


def _strings(block: np.ndarray, offset: int, width: int) -> np.ndarray:
    if width == 0:
        return np.full(len(block), "", dtype="<U1")
    return np.char.decode(_cut(block, offset, width).view(f"S{width}").ravel(), "utf-8")


def _vectorised(
    slots: list[_Slot], block: np.ndarray, columns: tuple[Column, ...]
) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    rows = len(block)
    for column, slot in zip(columns, slots):
        if slot.kind == "scalar":
            out[column.name] = (
                _cut(block, slot.offset, slot.dtype.itemsize)
                .view(slot.dtype)
                .ravel()
                .astype(column.dtype)
            )
        elif slot.kind == "string":
            out[column.name] = _strings(block, slot.offset, slot.width)
        elif slot.kind == "array":
            values = _cut(block, slot.offset, slot.width * slot.dtype.itemsize).view(slot.dtype)
            out[column.name] = values.reshape(rows, slot.width).astype(slot.dtype.newbyteorder("="))
        else:
            parts = [_strings(block, o, w) for o, w in slot.parts]
            lists = np.empty(rows, dtype=object)
            lists[:] = [list(row) for row in zip(*parts)] if parts else [[] for _ in range(rows)]
            out[column.name] = lists
    return out


def _per_message(
    decoder: Decoder, datas: list[bytes], index: np.ndarray, errors: list[str]
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    rows, good = [], []
    for i in index:
        try:
            rows.append(decoder.decode(datas[i]))
        except CdrError as error:
            errors.append(f"message {i}: {error}")
            continue
        good.append(i)
    transposed = list(zip(*rows)) if rows else [()] * len(decoder.columns)
    out: dict[str, np.ndarray] = {}
    for column, values in zip(decoder.columns, transposed):
        if column.kind == "scalar":
            out[column.name] = np.array(values, dtype=column.dtype)
        elif column.kind == "string":
            out[column.name] = np.array(values, dtype=str) if values else np.array([], dtype=str)
        else:
            array = np.empty(len(values), dtype=object)
            array[:] = list(values)
            out[column.name] = array
    return np.array(good, dtype=np.int64), out


def _as_rows(values: np.ndarray) -> np.ndarray:
    if values.dtype != object and values.ndim == 2:
        rows = np.empty(len(values), dtype=object)
        rows[:] = list(values)
        return rows
    return values


def _finish(column: Column, values: np.ndarray) -> np.ndarray:
    """Sequences of equal length become a 2-D array; ragged ones stay an object array."""
    if column.kind == "array" and values.dtype == object and len(values):
        if len({len(v) for v in values}) == 1:
            return np.stack(list(values))
    return values


def decode_columns(
    decoder: Decoder, datas: list[bytes]
) -> tuple[dict[str, np.ndarray], np.ndarray, list[str]]:
    """Columns of ``datas`` (serialized messages of ``decoder``'s type), in order.

    Returns the columns, the indices of the messages they hold (messages that do not match
    the definition are left out) and one error text per message left out.
    """
    count = len(datas)
    errors: list[str] = []
    lengths = np.fromiter((len(d) for d in datas), dtype=np.int64, count=count)
    parts: list[tuple[np.ndarray, dict[str, np.ndarray]]] = []
    leftover: list[np.ndarray] = []
    for length in np.unique(lengths):
        index = np.flatnonzero(lengths == length)
        first = datas[index[0]]
        try:
            if len(first) < HEADER_SIZE or first[1] not in LITTLE_ENDIAN_KINDS:
                raise _Unsupported("encapsulation")
            slots, checks = _layout(decoder.types, decoder.type_name, first)
        except (_Unsupported, struct.error, CdrError):
            leftover.append(index)
            continue
        block = np.frombuffer(b"".join(datas[i] for i in index), dtype=np.uint8).reshape(
            len(index), int(length)
        )
        same = block[:, 1] == first[1]
        for offset, value in checks:
            same &= _cut(block, offset, 4).view("<u4").ravel() == value
        if not same.all():
            leftover.append(index[~same])
            index, block = index[same], block[same]
        parts.append((index, _vectorised(slots, block, decoder.columns)))
    if leftover or not parts:
        parts.append(
            _per_message(
                decoder, datas, np.sort(np.concatenate(leftover or [np.zeros(0, np.int64)])), errors
            )
        )
    if len(parts) == 1:
        index, columns = parts[0]
        return {c.name: _finish(c, columns[c.name]) for c in decoder.columns}, index, errors
    index = np.concatenate([i for i, _ in parts])
    order = np.argsort(index, kind="stable")
    columns = {
        c.name: _finish(c, np.concatenate([_as_rows(p[c.name]) for _, p in parts])[order])
        for c in decoder.columns
    }
    return columns, index[order], errors
