"""Reading the station's text files (programs, symbols.csv, messages.csv, tags.csv, station.toml,
forms, users.json).

One decision for every loader: a file is UTF-8, with or without a byte order mark; a file that is
not valid UTF-8 is read as cp1251, which is what the Windows tools of the manual's era (Notepad,
Excel "CSV") write for Cyrillic text. A byte cp1251 does not define either is a `TextFileError`
naming the file and the position, never a UnicodeDecodeError. CSV rows come with their line number,
and a CSV the csv module refuses (a field over its size limit, a NUL) is a problem of that line.

A station folder is input like any other: only a regular file of at most MAX_BYTES is read, so a
name that is a link to /dev/zero, a FIFO, a device or a folder is a named problem instead of a
read that never ends or fills the memory, and a loop of symbolic links is named too (Python 3.11's
`Path.resolve` raises RuntimeError for one).

Its problems are phrases of netplc/words.py (`TextFileError.phrase`, a CSV line's problem), said in
the station's language by whoever reports them with a station; what the system says inside one
(an OS error, the csv module's own message) stays as it is.
"""

from __future__ import annotations

import csv
import os
import stat
from collections.abc import Iterator
from pathlib import Path

from netplc.words import Phrase, Say, WordedError, english, phrase, said

FALLBACK = "cp1251"
# The largest station text file read: the demo's largest is 20 KB, a full 8 K-word program with
# comments well under 1 MB; what is larger is a mistake (a log, an archive) and is not read whole.
MAX_BYTES = 16 * 1024 * 1024
MISSING = "does not exist"  # what file_problem says of a name with nothing there
_OPEN = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)  # a FIFO opens at once
# Decimal digits accepted in a whole number of a text file: past Python's int() conversion limit
# (4300 digits) int() raises, and no value of a station needs more than a few digits anyway.
MAX_DIGITS = 100


class TextFileError(WordedError):
    """A text file that cannot be read or decoded: `file:line: problem` (`file: problem` when the
    problem is the whole file's, line 0), the problem a phrase (`phrase`; `problem` its English)."""

    def __init__(self, source: str, line: int, name: str, /, **values: object) -> None:
        super().__init__(name, **values)
        self.source, self.line = source, line

    @property
    def problem(self) -> str:
        return str(said(english, self.phrase))

    def said(self, say: Say) -> str:
        text = said(say, self.phrase)
        return f"{self.source}:{self.line}: {text}" if self.line else f"{self.source}: {text}"

    def __str__(self) -> str:
        return self.said(english)


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
            raise TextFileError(source, line, "file not text", fallback=FALLBACK,
                                byte=data[e.start]) from None


def read_text(path: str | Path, what: str = "read file", limit: int = MAX_BYTES) -> str:
    """The text of `path` (see `decode`); TextFileError names the file and what it is (`what`, a
    phrase of netplc/words.py: "read program", "read tags"...)."""
    return decode(read_bytes(path, what, limit), str(path))


def read_bytes(path: str | Path, what: str = "read file", limit: int = MAX_BYTES) -> bytes:
    """The bytes of the regular file `path`, at most `limit` of them; TextFileError names the file
    and why it is not read (not a file, too large, a loop of links, no permission)."""
    source, named = str(path), phrase(what)
    try:
        fd = os.open(path, _OPEN)
    except OSError as e:
        raise TextFileError(source, 0, "file cannot read", what=named, error=e.strerror or e) from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise TextFileError(source, 0, "file not a file", what=named, kind=phrase(_kind(info.st_mode)))
        with open(fd, "rb", closefd=False) as f:
            data = f.read(limit + 1) if info.st_size <= limit else b""
    except OSError as e:
        raise TextFileError(source, 0, "file cannot read", what=named, error=e.strerror or e) from None
    finally:
        os.close(fd)
    if info.st_size > limit or len(data) > limit:
        raise TextFileError(source, 0, "file too large", what=named, mb=limit // 1024 // 1024)
    return data


def kind(mode: int) -> str:
    """What a file system entry of `mode` is, for a problem saying it is not what was expected."""
    return english(_kind(mode))


def _kind(mode: int) -> str:
    """The phrase of netplc/words.py naming what a file system entry of `mode` is."""
    for test, what in ((stat.S_ISREG, "kind file"), (stat.S_ISDIR, "kind folder"),
                       (stat.S_ISFIFO, "kind fifo"), (stat.S_ISCHR, "kind char"),
                       (stat.S_ISBLK, "kind block"), (stat.S_ISSOCK, "kind socket")):
        if test(mode):
            return what
    return "kind special"


def file_problem(path: Path, folder: bool = False) -> str | None:
    """Why `path` is not an existing regular file (with `folder`, an existing folder); None when
    it is. Links are followed."""
    try:
        mode = path.stat().st_mode
    except (FileNotFoundError, NotADirectoryError):  # nothing there, or a file where a folder is named
        return MISSING
    except OSError as e:
        return e.strerror or str(e)
    if stat.S_ISDIR(mode) if folder else stat.S_ISREG(mode):
        return None
    return f"is {kind(mode)}, not a {'folder' if folder else 'file'}"


def resolve(path: Path) -> Path:
    """`path` made absolute with every symbolic link followed; TextFileError for a loop of links."""
    try:
        return path.resolve()
    except (OSError, RuntimeError):  # Python 3.11 raises RuntimeError("Symlink loop ...")
        raise TextFileError(str(path), 0, "file link loop") from None


def confine(path: Path, folder: Path) -> Path:
    """`path` with its links followed, if that lies inside `folder`; TextFileError naming it if not
    (a station reads its own files only, unless its station.toml says allow_outside)."""
    real, root = resolve(path), resolve(folder)
    if not real.is_relative_to(root):
        raise TextFileError(str(path), 0, "file outside", real=real, root=root)
    return real


def csv_rows(text: str) -> Iterator[tuple[int, list[str] | Phrase]]:
    """(line number, row) of CSV text, or (line number, problem) for a line the csv module refuses.

    A row is one line: a quoted field that runs on over the next lines (a closing quote missing,
    or a name split in two by a line break) is a problem of the line it starts on, instead of a
    field silently made of several lines.
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
            yield start, (phrase("csv field long", n=csv.field_size_limit())
                          if "field larger than field limit" in str(e) else phrase("csv error", error=e))
        else:
            if reader.line_num > start:
                yield start, phrase("csv runs on", line=reader.line_num)
            else:
                yield start, row
        start = reader.line_num + 1


def whole_number(text: str) -> int | None:
    """A non-negative decimal integer of ASCII digits (str.isdigit() also takes '²'), else None."""
    value = text.strip()
    if not value.isascii() or not value.isdigit() or len(value) > MAX_DIGITS:
        return None
    return int(value)
