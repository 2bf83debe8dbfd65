"""CDR (XCDR1, little endian) decoders and encoders generated from parsed message definitions.

A decoder turns one serialized message into a flat tuple, one value per leaf field
(``header.stamp.sec``, ``header.frame_id``, ``force``...); an encoder turns such a tuple
back into the bytes rclpy's ``serialize_message`` gives (with zeroed padding, where rclpy
leaves whatever was in memory). Nested message fields are inlined;
runs of fixed-size fields are read or written with a single ``struct`` call whose padding is
worked out when the code is generated, so a typical message costs a few struct calls.
Alignment is relative to the end of the 4-byte encapsulation header, as CDR requires.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from hems_ros.codec.msgdefs import PRIMITIVES, DefinitionError, Field

HEADER_SIZE = 4
CDR_LE_HEADER = b"\x00\x01\x00\x00"
LITTLE_ENDIAN_KINDS = (0x01, 0x03)  # CDR_LE, PL_CDR_LE
SCALARS = {  # name: (struct code, size, numpy dtype)
    "bool": ("?", 1, np.bool_),
    "byte": ("B", 1, np.uint8),
    "char": ("B", 1, np.uint8),
    "int8": ("b", 1, np.int8),
    "uint8": ("B", 1, np.uint8),
    "int16": ("h", 2, np.int16),
    "uint16": ("H", 2, np.uint16),
    "int32": ("i", 4, np.int32),
    "uint32": ("I", 4, np.uint32),
    "int64": ("q", 8, np.int64),
    "uint64": ("Q", 8, np.uint64),
    "float32": ("f", 4, np.float32),
    "float64": ("d", 8, np.float64),
}


class CdrError(ValueError):
    """A message that does not match its definition."""


@dataclass(frozen=True)
class Column:
    """One leaf field of a flattened message."""

    name: str
    dtype: Any  # numpy dtype for scalars, ``object`` for strings and sequences
    kind: str  # "scalar", "string", "array" (numpy per message) or "list"


@dataclass(frozen=True)
class Decoder:
    type_name: str
    columns: tuple[Column, ...]
    decode: Callable[[bytes], tuple[Any, ...]]
    types: dict[str, list[Field]]


class _Emitter:
    """Generates straight-line Python for one message type, tracking static alignment."""

    def __init__(self, types: dict[str, list[Field]], helpers: dict[str, object]) -> None:
        self.types = types
        self.helpers = helpers
        self.lines: list[str] = []
        self.columns: list[Column] = []
        self.values: list[str] = []
        self.variables = 0
        self.modulus = 8  # o - HEADER_SIZE is known modulo this...
        self.phase = 0  # ...to equal this
        self.pending_fmt = ""
        self.pending_vars: list[str] = []
        self.pending_size = 0

    def var(self) -> str:
        self.variables += 1
        return f"v{self.variables}"

    def column(self, column: Column, variable: str) -> None:
        self.columns.append(column)
        self.values.append(variable)

    def flush(self) -> None:
        if self.pending_vars:
            targets = ", ".join(self.pending_vars) + ("," if len(self.pending_vars) == 1 else "")
            self.lines.append(
                f"{targets} = unpack_from('<{self.pending_fmt}', b, o); o += {self.pending_size}"
            )
        elif self.pending_size:
            self.lines.append(f"o += {self.pending_size}")
        self.pending_fmt, self.pending_vars, self.pending_size = "", [], 0

    def align(self, size: int) -> None:
        if size <= 1:
            return
        if size <= self.modulus:
            pad = (-self.phase) % size
            if pad:
                self.pending_fmt += f"{pad}x"
                self.pending_size += pad
                self.phase = (self.phase + pad) % self.modulus
            return
        self.flush()
        self.lines.append(self.dynamic_padding(size))
        self.modulus, self.phase = size, 0

    def dynamic_padding(self, size: int) -> str:
        return f"o += ({HEADER_SIZE} - o) % {size}"

    def advance(self, size: int) -> None:
        self.phase = (self.phase + size) % self.modulus

    def unknown_phase(self) -> None:
        self.flush()
        self.modulus, self.phase = 1, 0

    def scalar(self, primitive: str) -> str:
        code, size, _ = SCALARS[primitive]
        self.align(size)
        target = self.var()
        self.pending_fmt += code
        self.pending_vars.append(target)
        self.pending_size += size
        self.advance(size)
        return target

    def count(self) -> str:
        target = self.scalar("uint32")
        self.flush()
        return target

    def string(self) -> str:
        length = self.count()
        target = self.var()
        self.lines.append(f"{target} = str(b[o:o + {length} - 1], 'utf-8'); o += {length}")
        self.unknown_phase()
        return target

    def primitive_array(self, primitive: str, count: str | int) -> str:
        _, size, dtype = SCALARS[primitive]
        if isinstance(count, int):
            self.align(size)
            self.flush()
        elif size > 1:
            # Fast CDR pads to the element size only when a sequence has elements.
            self.flush()
            self.lines.append(f"if {count}: o += ({HEADER_SIZE} - o) % {size}")
        target = self.var()
        dtype_name = self.helper(f"dt_{primitive}", np.dtype(dtype))
        self.lines.append(
            f"{target} = frombuffer(b, {dtype_name}, {count}, o).copy(); o += {count} * {size}"
        )
        if isinstance(count, int):
            self.advance(count * size)
        else:
            self.unknown_phase()
        return target

    def helper(self, name: str, value: object) -> str:
        self.helpers[name] = value
        return name

    def field(self, field: Field, prefix: str) -> None:
        name = f"{prefix}{field.name}"
        if field.type == "wstring":
            raise DefinitionError(f"wstring field {name} is not supported")
        if field.array is None:
            if field.type == "string":
                self.column(Column(name, object, "string"), self.string())
            elif field.type in PRIMITIVES:
                self.column(
                    Column(name, np.dtype(SCALARS[field.type][2]), "scalar"),
                    self.scalar(field.type),
                )
            else:
                for sub in self.types[field.type]:
                    self.field(sub, f"{name}.")
            return
        count: str | int = self.count() if field.is_sequence else field.array
        if field.type in PRIMITIVES and field.type != "string":
            self.column(Column(name, object, "array"), self.primitive_array(field.type, count))
            return
        self.column(Column(name, object, "list"), self.element_list(field.type, count))

    def element_list(self, type_name: str, count: str | int) -> str:
        reader = f"read_{type_name.replace('/', '_')}"
        if reader not in self.helpers:
            self.helpers[reader] = (
                _read_string
                if type_name == "string"
                else _element_reader(type_name, self.types, self.helpers)
            )
        self.flush()
        target = self.var()
        self.lines.append(f"{target} = []")
        self.lines.append(f"for _ in range({count}):")
        self.lines.append(f"    item, o = {reader}(b, o)")
        self.lines.append(f"    {target}.append(item)")
        self.unknown_phase()
        return target

    def message(self, type_name: str, prefix: str = "") -> None:
        if type_name not in self.types:
            raise DefinitionError(f"no definition of {type_name}")
        for field in self.types[type_name]:
            self.field(field, prefix)
        self.flush()


def _read_string(b: bytes, o: int) -> tuple[str, int]:
    o += (HEADER_SIZE - o) % 4
    (length,) = struct.unpack_from("<I", b, o)
    return str(b[o + 4 : o + 3 + length], "utf-8"), o + 4 + length


def _compile(name: str, emitter: _Emitter, body_result: str, signature: str) -> Callable[..., Any]:
    source = f"def {name}({signature}):\n    o = {'o0' if 'o0' in signature else HEADER_SIZE}\n"
    source += "".join(f"    {line}\n" for line in emitter.lines)
    source += f"    return {body_result}\n"
    namespace: dict[str, object] = {"unpack_from": struct.unpack_from, "frombuffer": np.frombuffer}
    namespace.update(emitter.helpers)
    exec(compile(source, f"<cdr {name}>", "exec"), namespace)  # noqa: S102 - generated from parsed definitions only
    return cast(Callable[..., Any], namespace[name])


def _element_reader(
    type_name: str, types: dict[str, list[Field]], helpers: dict[str, object]
) -> Callable[..., Any]:
    emitter = _Emitter(types, helpers)
    emitter.modulus = 1
    emitter.message(type_name)
    pairs = ", ".join(f"{c.name!r}: {v}" for c, v in zip(emitter.columns, emitter.values))
    return _compile("read_element", emitter, f"{{{pairs}}}, o", "b, o0")


def build_decoder(type_name: str, types: dict[str, list[Field]]) -> Decoder:
    """A decoder of ``type_name`` from the parsed definitions of it and its dependencies."""
    emitter = _Emitter(types, {})
    emitter.message(type_name)
    result = "(" + "".join(f"{v}, " for v in emitter.values) + ")"
    body = cast(Callable[[bytes], tuple[Any, ...]], _compile("decode_body", emitter, result, "b"))

    def decode(data: bytes) -> tuple[Any, ...]:
        if len(data) < HEADER_SIZE or data[1] not in LITTLE_ENDIAN_KINDS:
            raise CdrError(
                f"{type_name}: not little-endian CDR (encapsulation {bytes(data[:4]).hex()})"
            )
        try:
            return body(data)
        except (struct.error, ValueError, UnicodeDecodeError) as error:
            raise CdrError(f"{type_name}: {error}") from None

    return Decoder(type_name, tuple(emitter.columns), decode, types)


class _EncodeEmitter(_Emitter):
    """Generates the writer of one message type: the decoder's layout, packed instead of read.

    Scalars, strings and nested messages only: the graph's hot messages have no arrays, and
    a sequence's padding rules (see :meth:`_Emitter.primitive_array`) would need tests of
    their own before anything is published with them.
    """

    def field(self, field: Field, prefix: str) -> None:
        if field.array is not None:
            raise DefinitionError(
                f"field {prefix}{field.name}: the encoder writes no arrays or sequences"
            )
        super().field(field, prefix)

    def flush(self) -> None:
        if self.pending_vars:
            self.lines.append(f"out += pack('<{self.pending_fmt}', {', '.join(self.pending_vars)})")
        elif self.pending_size:
            self.lines.append(f"out += bytes({self.pending_size})")
        self.pending_fmt, self.pending_vars, self.pending_size = "", [], 0

    def dynamic_padding(self, size: int) -> str:
        return f"out += bytes(({HEADER_SIZE} - len(out)) % {size})"

    def string(self) -> str:
        self.align(4)
        self.flush()
        target = self.var()
        self.lines.append(
            f"t = {target}.encode('utf-8'); out += pack('<I', len(t) + 1); out += t; "
            f"out += b'\\x00'"
        )
        self.unknown_phase()
        return target


@dataclass(frozen=True)
class Encoder:
    type_name: str
    columns: tuple[Column, ...]
    encode: Callable[[tuple[Any, ...]], bytes]


def build_encoder(type_name: str, types: dict[str, list[Field]]) -> Encoder:
    """An encoder of ``type_name``: a flat tuple in the decoder's column order -> CDR bytes."""
    emitter = _EncodeEmitter(types, {})
    emitter.message(type_name)
    source = "def encode_body(values):\n"
    source += f"    ({''.join(v + ', ' for v in emitter.values)}) = values\n"
    source += "    out = bytearray(HEAD)\n"
    source += "".join(f"    {line}\n" for line in emitter.lines)
    source += "    return bytes(out)\n"
    namespace: dict[str, object] = {"pack": struct.pack, "HEAD": CDR_LE_HEADER}
    exec(compile(source, f"<cdr encode {type_name}>", "exec"), namespace)  # noqa: S102 - parsed definitions only
    body = cast(Callable[[tuple[Any, ...]], bytes], namespace["encode_body"])

    def encode(values: tuple[Any, ...]) -> bytes:
        try:
            return body(values)
        except (struct.error, ValueError, TypeError, AttributeError) as error:
            raise CdrError(f"{type_name}: cannot encode {values!r}: {error}") from None

    return Encoder(type_name, tuple(emitter.columns), encode)
