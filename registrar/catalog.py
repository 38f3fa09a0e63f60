"""The message catalog: what an NMSG number means (`messages.csv`: number,group,type,text).

NMSG carries only a number, so the text is looked up here when the record is written and stored
with it: an archive then stays readable after the catalog changes or on another machine.
"""

from __future__ import annotations

import csv
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from netplc.problems import Problems

MESSAGE_TYPES = {0: "info", 1: "warning", 2: "alarm", 3: "critical"}  # docs/architecture.md section 8


class CatalogError(Problems):
    """A catalog that cannot be used; every problem is named `file:line: message`."""


@dataclass(frozen=True, slots=True)
class Message:
    number: int
    grp: int
    type: int
    text: str


class Catalog:
    def __init__(self, messages: dict[int, Message] | None = None) -> None:
        self._messages: dict[int, Message] = dict(messages or {})

    @classmethod
    def load(cls, path: str | Path) -> Catalog:
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8-sig")
        except (OSError, UnicodeDecodeError) as e:
            raise CatalogError([f"{path}:0: cannot read the message catalog: {e}"]) from None
        problems: list[str] = []
        messages: dict[int, Message] = {}
        lines: dict[int, int] = {}
        for lineno, row in enumerate(csv.reader(text.splitlines()), start=1):
            if not row or not "".join(row).strip() or row[0].lstrip().startswith(("#", ";")):
                continue
            if lineno == 1 and not row[0].strip().isdigit():
                continue  # a header line
            try:
                message = _parse_row(row)
            except ValueError as e:
                problems.append(f"{path}:{lineno}: {e}")
                continue
            if message.number in messages:
                problems.append(f"{path}:{lineno}: message {message.number} is already defined "
                                f"on line {lines[message.number]}")
                continue
            messages[message.number] = message
            lines[message.number] = lineno
        if problems:
            raise CatalogError(problems)
        return cls(messages)

    def get(self, number: int) -> Message | None:
        return self._messages.get(number)

    def text_for(self, number: int) -> str:
        message = self._messages.get(number)
        return message.text if message else f"unknown message {number} (not in the catalog)"

    def __iter__(self) -> Iterator[Message]:
        return iter(sorted(self._messages.values(), key=lambda m: m.number))

    def __len__(self) -> int:
        return len(self._messages)


def _parse_row(row: list[str]) -> Message:
    if len(row) < 4:
        raise ValueError(f"expected number,group,type,text but found {len(row)} field(s)")
    number = _integer(row[0], "number")
    grp = _integer(row[1], "group")
    kind = _integer(row[2], "type")
    if kind not in MESSAGE_TYPES:
        raise ValueError(f"type {kind} is not one of 0 info, 1 warning, 2 alarm, 3 critical")
    text = ",".join(row[3:]).strip()  # an unquoted comma in the text is still part of it
    if not text:
        raise ValueError(f"message {number} has no text")
    return Message(number, grp, kind, text)


def _integer(field: str, name: str) -> int:
    value = field.strip()
    if not value.isdigit():
        raise ValueError(f"{name} {value!r} is not a non-negative whole number")
    return int(value)
