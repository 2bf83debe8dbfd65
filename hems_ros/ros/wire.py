"""Serialized (CDR) messages for the graph's 100 Hz streams, without rclpy message objects.

On the graph's hot topics (encoder, wire tension and force, duty, controller status,
simulation state) the nodes publish bytes and subscribe with ``raw=True``: rclpy then skips
building a Python message object and converting it field by field, which cost more than the
nodes' own work per message (benchmarks/bench_graph.py, docs/design.md). The bytes
are exactly what a typed publisher sends, so ``ros2 topic echo``, the recorder and any other
subscriber see ordinary messages.

A codec reads and writes one message type as a named tuple of its leaf fields, nested names
joined by ``_`` (``header_stamp_sec``, ``measurement_stamp_nanosec``); the layout comes from
the installed ``.msg`` definitions through :mod:`hems_ros.codec.cdr`. No rclpy import here.
"""

from __future__ import annotations

import importlib
from collections import namedtuple
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

from hems_ros.codec import cdr, msgdefs

NS_PER_S = 1_000_000_000


def message_class(type_name: str) -> type:
    """The generated Python class of ``pkg/msg/Type`` (imported on demand)."""
    package, _, name = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


@dataclass(frozen=True)
class Codec:
    fields: Any  # named tuple class of the leaf fields, in CDR order
    encode: Callable[[tuple], bytes]  # CdrError names the type and the bad value
    _decode: Callable[[bytes], tuple]

    def decode(self, data: bytes) -> tuple:
        """The message as :attr:`fields`; :class:`hems_ros.codec.cdr.CdrError` if malformed."""
        return self.fields._make(self._decode(data))


@lru_cache(maxsize=None)
def codec(msg_type: type) -> Codec:
    """The codec of a rosidl message class such as ``hems_msgs.msg.EncoderReading``."""
    type_name = f"{msg_type.__module__.split('.')[0]}/msg/{msg_type.__name__}"
    types = msgdefs.parse_full_definition(type_name, msgdefs.full_definition(type_name))
    decoder = cdr.build_decoder(type_name, types)
    try:
        encode = cdr.build_encoder(type_name, types).encode
    except msgdefs.DefinitionError as error:
        encode = _unencodable(error)  # read-only here: a type with sequences
    fields = namedtuple(  # type: ignore[misc]  # a class per message type, named at run time
        msg_type.__name__ + "Fields", [c.name.replace(".", "_") for c in decoder.columns]
    )
    return Codec(fields, encode, decoder.decode)


def _unencodable(error: Exception) -> Callable[[tuple], bytes]:
    def encode(_values: tuple) -> bytes:
        raise error

    return encode


def stamp(time_s: float) -> tuple[int, int]:
    """(sec, nanosec) of a builtin_interfaces/Time for ``time_s`` seconds."""
    return stamp_ns(int(round(time_s * NS_PER_S)))


def stamp_ns(nanoseconds: int) -> tuple[int, int]:
    """(sec, nanosec) of a builtin_interfaces/Time for an integer clock reading in ns."""
    return divmod(nanoseconds, NS_PER_S)


def seconds_of(sec: int, nanosec: int) -> float:
    return sec + nanosec * 1e-9
