"""Which topics a recording, a load or a replay takes: exact names and/or a regular expression."""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass


def record_regex(namespace: str = "/hems") -> str:
    """The whole graph under ``namespace``, diagnostics and sim time."""
    return re.escape(namespace.rstrip("/")) + r"/.*|/diagnostics|/clock"


#: What ``hems record`` takes when given nothing: the whole HEMS graph, diagnostics and sim time.
DEFAULT_RECORD_REGEX = record_regex()


@dataclass(frozen=True)
class TopicSelection:
    """Topics named in ``names`` or fully matching ``pattern``; everything when both are empty."""

    names: frozenset[str] = frozenset()
    pattern: re.Pattern[str] | None = None

    @classmethod
    def of(cls, topics: Iterable[str] | None = None, regex: str | None = None) -> TopicSelection:
        try:
            pattern = re.compile(regex) if regex else None
        except re.error as error:
            raise ValueError(f"invalid topic regex {regex!r}: {error}") from None
        return cls(frozenset(t for t in (topics or ()) if t), pattern)

    @property
    def everything(self) -> bool:
        return not self.names and self.pattern is None

    def matches(self, topic: str) -> bool:
        if self.everything or topic in self.names:
            return True
        return self.pattern is not None and self.pattern.fullmatch(topic) is not None

    def describe(self) -> str:
        parts = sorted(self.names) + ([f"regex {self.pattern.pattern!r}"] if self.pattern else [])
        return ", ".join(parts) if parts else "all topics"
