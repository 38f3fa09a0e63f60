"""Reading the station's text files (programs, symbols.csv, messages.csv, station.toml, forms).

One decision for every loader: a file is UTF-8, with or without a byte order mark; a file that is
not valid UTF-8 is read as cp1251, which is what the Windows tools of the manual's era (Notepad,
Excel "CSV") write for Cyrillic text. A byte cp1251 does not define either is a `TextFileError`
naming the file and the position, never a UnicodeDecodeError. CSV rows come with their line number,
and a CSV the csv module refuses (a field over its size limit, a NUL) is a problem of that line.
"""

from __future__ import annotations

import csv
from collections.abc import Iterator
from pathlib import Path

FALLBACK = "cp1251"
# Decimal digits accepted in a whole number of a text file: past Python's int() conversion limit
# (4300 digits) int() raises, and no value of a station needs more than a few digits anyway.
MAX_DIGITS = 100


class TextFileError(ValueError):
    """A text file that cannot be read or decoded: `file:line: problem` (`file: problem` when the
    problem is the whole file's, line 0)."""

    def __init__(self, source: str, line: int, problem: str) -> None:
        self.source, self.line, self.problem = source, line, problem
        super().__init__(f"{source}:{line}: {problem}" if line else f"{source}: {problem}")


def decode(data: bytes, source: str) -> str:
    """UTF-8 (a leading BOM dropped), else cp1251; TextFileError names the line of the first byte
    that neither defines."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        try:
            return data.decode(FALLBACK)
        except UnicodeDecodeError as e:
            line = data.count(b"\n", 0, e.start) + 1
            raise TextFileError(source, line, f"neither UTF-8 nor {FALLBACK} text "
                                              f"(byte 0x{data[e.start]:02X})") from None


def read_text(path: str | Path, what: str = "the file") -> str:
    """The text of `path` (see `decode`); TextFileError names the file and what it is."""
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        raise TextFileError(str(path), 0, f"cannot read {what}: {e.strerror or e}") from None
    return decode(data, str(path))


def csv_rows(text: str) -> Iterator[tuple[int, list[str] | str]]:
    """(line number, row) of CSV text, or (line number, problem) for a line the csv module refuses.

    The line number is that of the row's first line (a quoted field may span lines).
    """
    lines = iter(text.splitlines())
    reader = csv.reader(lines)
    start = 1
    while True:
        try:
            row = next(reader)
        except StopIteration:
            return
        except csv.Error as e:
            problem = str(e)
            if "field larger than field limit" in problem:
                problem = f"a field is longer than {csv.field_size_limit()} characters"
            yield start, problem
        else:
            yield start, row
        start = reader.line_num + 1


def whole_number(text: str) -> int | None:
    """A non-negative decimal integer of ASCII digits (str.isdigit() also takes '²'), else None."""
    value = text.strip()
    if not value.isascii() or not value.isdigit() or len(value) > MAX_DIGITS:
        return None
    return int(value)
