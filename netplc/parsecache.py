"""Parsed programs kept on disk between starts (issue 28: start <= 1.3x its imports).

Once the compiled program comes from `codecache.py`, parsing the program's text is most of what a
start adds to its imports (164 ms for 8 K words). What `parse` makes depends only on the text,
where it came from (its diagnostics and `Program.source` name the file), the symbols given and the
parser, so the parsed program is marshalled (plain tuples, no code) into a file named by a SHA-256
key over all of them; the parser's version is the source of the modules it is made of. The file's
header holds the key and a SHA-256 of the payload, so a damaged or foreign file is found, logged,
ignored and written again. The folder is bounded (`MAX_FILES` programs, `MAX_BYTES` in all; the
least recently used go first): a station keeps its program and its simulated nodes' there. Failing
to read or write the cache only costs the parse: a start never depends on it.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import logging
import marshal
import operator
import os
import tempfile
from pathlib import Path

from netplc import address, problems, textfile
from netplc.codecache import cache_key
from netplc.functions import registry
from netplc.program import Instr, Program, parse, read_program_text

logger = logging.getLogger(__name__)
PREFIX = "parsed-"
SUFFIX = ".bin"
MAX_FILES = 16
MAX_BYTES = 64 << 20
_ROW = operator.attrgetter("op", "c", "n", "s", "d", "r", "target", "addr", "line", "text")  # Instr's fields


@functools.cache
def _parser_version() -> bytes:
    """The source of the parser and of what decides what it accepts (addresses, function specs)."""
    folder = Path(registry.__file__ or "").parent
    modules = [Path(m.__file__ or "") for m in (address, problems, textfile, registry)]
    sources = [Path(__file__).with_name("program.py"), *modules, *sorted(folder.glob("*.py"))]
    return b"".join(p.read_bytes() for p in sources)


def program_key(text: str, source: str, symbols: dict[str, int]) -> bytes:
    """The key of what `parse(text, source, symbols)` makes with this parser and Python."""
    return cache_key(_parser_version(), str(marshal.version), source, text, repr(sorted(symbols.items())))


class ParseCache:
    """One folder of parsed programs, each in a file of its own."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)

    def _path(self, key: bytes) -> Path:
        return self.folder / f"{PREFIX}{key.hex()[:32]}{SUFFIX}"

    def load(self, key: bytes, source: str) -> Program | None:
        """The program stored under `key` (its `source` named again), or None: missing, another
        key, or damaged (logged)."""
        path = self._path(key)
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            return None  # the first start of this program
        except OSError as e:
            logger.warning("parsed program %s not used, parsing again: %s", path, e)
            return None
        try:
            return self._decode(data, key, source, path)
        except (ValueError, EOFError, TypeError) as e:
            logger.warning("parsed program %s not used, parsing again: %s", path, e)
            return None

    @staticmethod
    def _decode(data: bytes, key: bytes, source: str, path: Path) -> Program:
        digest = data[len(key):len(key) + 32]
        payload = data[len(key) + 32:]
        if not data.startswith(key) or hashlib.sha256(payload).digest() != digest:
            raise ValueError("damaged (its checksum differs) or of another program")
        symbols, words, rows = marshal.loads(payload)
        if not (isinstance(symbols, dict) and isinstance(words, int) and isinstance(rows, list)):
            raise TypeError("not a parsed program")
        program = Program([Instr(*row) for row in rows], symbols, source, words)
        with contextlib.suppress(OSError):
            os.utime(path)  # recently used: the last to go when the folder is full
        return program

    def store(self, key: bytes, program: Program) -> None:
        """Write `program` under `key` (atomically), then drop the least recently used files beyond
        the bounds; a folder that cannot be written is left alone."""
        rows = [_ROW(i) for i in program.instrs]
        payload = marshal.dumps((program.symbols, program.words, rows))
        path = self._path(key)
        tmp: Path | None = None
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            fd, name = tempfile.mkstemp(prefix=PREFIX, suffix=".tmp", dir=self.folder)  # one per writer
            tmp = Path(name)
            with os.fdopen(fd, "wb") as f:
                f.write(key + hashlib.sha256(payload).digest() + payload)
            os.replace(tmp, path)
            self._bound()
        except OSError as e:  # each start parses then: slower, never wrong
            logger.warning("parsed program not kept in %s: %s", self.folder, e)
            if tmp is not None:
                with contextlib.suppress(OSError):
                    tmp.unlink(missing_ok=True)

    def _bound(self) -> None:
        entries = []
        for p in self.folder.glob(f"{PREFIX}*{SUFFIX}"):
            with contextlib.suppress(FileNotFoundError):  # another process's bound removed it
                st = p.stat()
                entries.append((st.st_mtime_ns, st.st_size, p))
        entries.sort(reverse=True)  # newest first: the one just written stays
        total = 0
        for count, (_, size, p) in enumerate(entries):
            total += size
            if count > 0 and (count >= MAX_FILES or total > MAX_BYTES):
                p.unlink(missing_ok=True)


def parse_file_cached(path: str | Path, symbols: dict[str, int] | None, cache: ParseCache) -> Program:
    """`parse_file(path, symbols)`, taken from `cache` when it holds this text's parse, else parsed
    and stored there. A program with errors raises ProgramError and is not stored."""
    path = Path(path)
    text = read_program_text(path)
    source, symbols = str(path), dict(symbols or {})
    key = program_key(text, source, symbols)
    program = cache.load(key, source)
    if program is None:
        program = parse(text, source=source, symbols=symbols)
        cache.store(key, program)
    return program

