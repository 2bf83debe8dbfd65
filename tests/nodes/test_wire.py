"""The serialized messages of the graph's hot topics against rclpy's own serialization."""

from __future__ import annotations

import math

import pytest
from hems_msgs.msg import (
    ActuatorState,
    ControllerStatus,
    DutyCommand,
    EncoderReading,
    SupervisorStatus,
    WireForce,
)
from rclpy.serialization import deserialize_message, serialize_message

from hems_ros.codec.cdr import CdrError
from hems_ros.codec.msgdefs import DefinitionError
from hems_ros.ros.wire import codec, seconds_of, stamp

HOT_TYPES = (EncoderReading, WireForce, DutyCommand, ControllerStatus, ActuatorState)


def _filled(msg_type, text: str):
    """A message with every leaf set to a value of its own (strings of ``text``'s length)."""
    message = msg_type()
    message.header.stamp.sec, message.header.stamp.nanosec = 1_795_000_123, 987_654_321
    message.header.frame_id = text
    for number, name in enumerate(msg_type.get_fields_and_field_types(), start=1):
        kind = msg_type.get_fields_and_field_types()[name]
        if kind == "string":
            setattr(message, name, text + name[: len(text) % 5])
        elif kind == "double":
            setattr(message, name, number * 1.25e-3 - 0.5)
        elif kind == "boolean":
            setattr(message, name, number % 2 == 1)
        elif kind in ("uint32", "int64"):
            setattr(message, name, 1000 * number + 7)
        elif kind == "builtin_interfaces/Time":
            getattr(message, name).sec, getattr(message, name).nanosec = (
                number,
                999_999_000 + number,
            )
    return message


@pytest.mark.parametrize("msg_type", HOT_TYPES, ids=lambda t: t.__name__)
@pytest.mark.parametrize("text", ["", "a", "ab", "abc", "index", "thumb_abduction"])
def test_codec_reads_and_writes_what_rclpy_does(msg_type, text):
    # string lengths 0-15 move every later field through each alignment phase
    c = codec(msg_type)
    message = _filled(msg_type, text)
    data = serialize_message(message)
    values = c.decode(data)
    for name in msg_type.get_fields_and_field_types():
        if name not in ("header",) and not hasattr(getattr(message, name), "sec"):
            assert getattr(values, name) == getattr(message, name), name
    assert values.header_stamp_nanosec == 987_654_321 and values.header_frame_id == text
    encoded = c.encode(values)
    # rclpy leaves its padding bytes uninitialised, so the bytes are compared through a
    # typed decode, and the lengths (same layout) directly
    assert len(encoded) == len(data)
    assert deserialize_message(encoded, msg_type) == message
    assert c.decode(encoded) == values


def test_encoder_reading_fields_are_named_by_their_path():
    fields = codec(DutyCommand).fields._fields
    assert fields == (
        "header_stamp_sec",
        "header_stamp_nanosec",
        "header_frame_id",
        "finger",
        "duty_percent",
        "measurement_stamp_sec",
        "measurement_stamp_nanosec",
        "sequence",
    )


def test_encode_names_the_type_and_the_bad_value():
    c = codec(WireForce)
    good = c.decode(serialize_message(WireForce(finger="index", force=3.0)))
    with pytest.raises(CdrError, match="WireForce.*not-a-number"):
        c.encode(good._replace(force="not-a-number"))
    with pytest.raises(CdrError, match="WireForce"):
        c.decode(serialize_message(WireForce(finger="index"))[:20])


def test_a_status_with_string_lists_is_read_and_refused_for_writing():
    """The units and controllers read the supervisor's status serialized; the encoder
    writes no sequences, so the codec reads it only."""
    status = SupervisorStatus(
        state=SupervisorStatus.FAULT,
        state_name="FAULT",
        faults=["index: heartbeat stale (409 ms without a message)", ""],
        fault_fingers=["index"],
    )
    status.header.stamp.sec, status.header.stamp.nanosec = 1_795_000_001, 20_000_000
    c = codec(SupervisorStatus)
    message = c.decode(serialize_message(status))
    assert (message.header_stamp_sec, message.header_stamp_nanosec) == (1_795_000_001, 20_000_000)
    assert message.state == SupervisorStatus.FAULT and message.state_name == "FAULT"
    assert list(message.faults) == list(status.faults)
    assert list(message.fault_fingers) == ["index"]
    with pytest.raises(DefinitionError, match="faults"):
        c.encode(message)


def test_stamp_round_trip():
    assert stamp(12.5) == (12, 500_000_000)
    # float seconds of today's epoch resolve 240 ns; the stamp keeps what they hold
    sec, nanosec = stamp(1_795_000_000.25)
    assert sec == 1_795_000_000 and abs(nanosec - 250_000_000) < 500
    assert math.isclose(seconds_of(*stamp(1234.567891)), 1234.567891, abs_tol=1e-9)
