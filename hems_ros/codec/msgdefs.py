"""ROS 2 message definitions: installed ``.msg`` files to rosbag2 ``ros2msg`` text and back.

rosidl installs every interface as ``<prefix>/share/<package>/msg/<Type>.msg`` (plus a
``.json`` type description holding the RIHS01 type hash). A bag schema carries the complete
definition: the top-level text first, then every dependency after a two-line separator
(80 ``=`` and ``MSG: pkg/msg/Type``), as specified in rosbag2's
``docs/message_definition_encoding.md``. Reading parses that text back, so a bag decodes
without the interface packages installed.
"""

from __future__ import annotations

import json
import os
import re
import sys
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

SEPARATOR = "=" * 80
PRIMITIVES = frozenset(
    {
        "bool",
        "byte",
        "char",
        "int8",
        "uint8",
        "int16",
        "uint16",
        "int32",
        "uint32",
        "int64",
        "uint64",
        "float32",
        "float64",
        "string",
        "wstring",
    }
)
UNBOUNDED = -1
_FIELD = re.compile(
    r"^(?P<type>[A-Za-z][\w/]*)(?:<=(?P<strbound>\d+))?"
    r"(?:\[(?P<array>(?:<=)?\d*)\])?\s+(?P<name>[A-Za-z]\w*)(?P<rest>.*)$"
)
_SECTION = re.compile(r"^={80}\n(?:MSG|IDL): (\S+)\n", re.MULTILINE)


class DefinitionError(ValueError):
    """A message definition that cannot be found or parsed."""


@dataclass(frozen=True)
class Field:
    name: str
    type: str  # a primitive name or a full name ``pkg/msg/Type``
    array: int | None  # None: scalar; UNBOUNDED: sequence; n >= 0: fixed array of n
    bounded: bool = False  # ``T[<=n]``: a sequence with an upper bound (CDR like UNBOUNDED)

    @property
    def is_sequence(self) -> bool:
        return self.array is not None and (self.array == UNBOUNDED or self.bounded)


def full_name(type_name: str, package: str | None = None) -> str:
    """``pkg/Type``, ``pkg/msg/Type`` or (inside ``package``) ``Type`` -> ``pkg/msg/Type``."""
    parts = type_name.split("/")
    if len(parts) == 3:
        return type_name
    if len(parts) == 2:
        return f"{parts[0]}/msg/{parts[1]}"
    if type_name == "Header":
        return "std_msgs/msg/Header"
    if package is None:
        raise DefinitionError(f"type {type_name!r} has no package")
    return f"{package}/msg/{type_name}"


def parse_msg(text: str, package: str) -> list[Field]:
    """Fields of one ``.msg`` text (constants and comments dropped, defaults ignored)."""
    fields = []
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        match = _FIELD.match(line)
        if match is None:
            raise DefinitionError(f"cannot parse message definition line {raw!r}")
        rest = match["rest"].strip()
        if rest.startswith("="):
            continue
        base = match["type"]
        base = base if base in PRIMITIVES else full_name(base, package)
        array_spec = match["array"]
        if array_spec is None:
            array, bounded = None, False
        elif array_spec == "":
            array, bounded = UNBOUNDED, False
        elif array_spec.startswith("<="):
            array, bounded = int(array_spec[2:]), True
        else:
            array, bounded = int(array_spec), False
        fields.append(Field(match["name"], base, array, bounded))
    return fields


def share_prefixes() -> list[Path]:
    """Install prefixes to search: ``AMENT_PREFIX_PATH`` entries, then this interpreter's."""
    entries = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    entries.append(sys.prefix)
    return list(dict.fromkeys(Path(p) for p in entries))


def _installed_file(type_name: str, suffix: str) -> Path | None:
    package, kind, name = full_name(type_name).split("/")
    for prefix in share_prefixes():
        candidate = prefix / "share" / package / kind / f"{name}{suffix}"
        if candidate.is_file():
            return candidate
    return None


@lru_cache(maxsize=None)
def msg_text(type_name: str) -> str:
    """The installed ``.msg`` text of ``type_name`` (trailing blank lines removed)."""
    path = _installed_file(type_name, ".msg")
    if path is None:
        raise DefinitionError(
            f"no installed definition of {full_name(type_name)} under "
            + ", ".join(str(p / 'share') for p in share_prefixes())
        )
    return path.read_text(encoding="utf-8").rstrip("\n")


@lru_cache(maxsize=None)
def full_definition(type_name: str) -> str:
    """The complete ``ros2msg`` definition of ``type_name`` with all nested dependencies."""
    root = full_name(type_name)
    order: list[str] = []

    def visit(name: str) -> None:
        package = name.split("/")[0]
        for field in parse_msg(msg_text(name), package):
            if field.type not in PRIMITIVES and field.type not in order and field.type != root:
                order.append(field.type)
                visit(field.type)

    visit(root)
    sections = [msg_text(root)]
    sections += [f"{SEPARATOR}\nMSG: {name}\n{msg_text(name)}" for name in order]
    return "\n".join(sections)


@lru_cache(maxsize=None)
def type_hash(type_name: str) -> str:
    """The RIHS01 hash rosidl recorded for ``type_name``, or '' if none is installed."""
    path = _installed_file(type_name, ".json")
    if path is None:
        return ""
    name = full_name(type_name)
    for entry in json.loads(path.read_text(encoding="utf-8")).get("type_hashes", []):
        if entry.get("type_name") == name:
            return str(entry.get("hash_string", ""))
    return ""


def parse_full_definition(type_name: str, text: str) -> dict[str, list[Field]]:
    """Parse a complete ``ros2msg`` definition into fields per full type name."""
    root = full_name(type_name)
    types: dict[str, list[Field]] = {}
    matches = list(_SECTION.finditer(text))
    head_end = matches[0].start() if matches else len(text)
    types[root] = parse_msg(text[:head_end], root.split("/")[0])
    for index, match in enumerate(matches):
        end = matches[index + 1].start() if index + 1 < len(matches) else len(text)
        name = full_name(match[1])
        types[name] = parse_msg(text[match.end() : end], name.split("/")[0])
    missing = {
        f.type
        for fields in types.values()
        for f in fields
        if f.type not in PRIMITIVES and f.type not in types
    }
    if missing:
        raise DefinitionError(f"definition of {root} lacks {', '.join(sorted(missing))}")
    return types
