"""The message catalog: what an NMSG number means (`messages.csv`: number,group,type,text).

NMSG carries only a number, so the text is looked up here when the record is written and stored
with it: an archive then stays readable after the catalog changes or on another machine.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from netplc.problems import Problem, Problems
from netplc.textfile import TextFileError, csv_rows, read_text, whole_number
from netplc.words import Phrase, phrase
from registrar.words import RowError, english

MESSAGE_TYPES = {0: "info", 1: "warning", 2: "alarm", 3: "critical"}  # docs/architecture.md section 8
INT64_MAX = 2**63 - 1  # the archive's INTEGER columns hold a signed 64-bit value


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
            text = read_text(path, "read messages")
        except TextFileError as e:
            raise CatalogError([e]) from None
        problems: list[str | Problem] = []
        messages: dict[int, Message] = {}
        lines: dict[int, int] = {}
        for lineno, row in csv_rows(text):
            if isinstance(row, Phrase):
                problems.append(Problem(f"{path}:{lineno}", row))
                continue
            if not row or not "".join(row).strip() or row[0].lstrip().startswith(("#", ";")):
                continue
            if lineno == 1 and not row[0].strip().isdigit():
                continue  # a header line
            try:
                message = _parse_row(row)
            except RowError as e:
                problems.append(Problem(f"{path}:{lineno}", e.phrase, english))
                continue
            if message.number in messages:
                problems.append(Problem(f"{path}:{lineno}", phrase("msg defined", number=message.number,
                                                                   line=lines[message.number]), english))
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
        raise RowError("msg fields", n=len(row))
    number = _integer(row[0], "number")
    grp = _integer(row[1], "group")
    kind = _integer(row[2], "type")
    if kind not in MESSAGE_TYPES:
        raise RowError("msg type", kind=kind)
    text = ",".join(row[3:]).strip()  # an unquoted comma in the text is still part of it
    if not text:
        raise RowError("msg no text", number=number)
    return Message(number, grp, kind, text)


def _integer(field: str, name: str) -> int:
    value = whole_number(field)
    if value is None:
        raise RowError("msg not whole", name=name, text=_show(field.strip()))
    if value > INT64_MAX:
        raise RowError("msg past", name=name, value=value, most=INT64_MAX)
    return value


def _show(text: str) -> str:
    return repr(text) if len(text) <= 40 else repr(text[:37]) + "..."
