"""The compiled program's code object, kept on disk between starts (issue 16: start <= 0.5 s).

Compiling an 8 K-word program to Python and then to bytecode is most of a station's start. The
code object depends only on the program, the compiler and the Python that made it, so it is
marshalled into a file whose header holds Python's bytecode magic and a SHA-256 key over all of
them; a file whose header differs, or that does not unmarshal to a code object, is ignored and
rebuilt. Failing to read or write the cache only costs the compile: the station never depends on it.
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import marshal
import os
from importlib.util import MAGIC_NUMBER
from pathlib import Path
from types import CodeType

logger = logging.getLogger(__name__)
PREFIX = "program-"
SUFFIX = ".code"


def cache_key(*parts: bytes | str) -> bytes:
    """SHA-256 over the Python bytecode magic and `parts` (each length-prefixed, so none runs into
    the next)."""
    h = hashlib.sha256(MAGIC_NUMBER)
    for part in parts:
        data = part.encode() if isinstance(part, str) else part
        h.update(len(data).to_bytes(8, "little"))
        h.update(data)
    return h.digest()


class CodeCache:
    """One folder of marshalled code objects; only the newest program's file is kept."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)

    def _path(self, key: bytes) -> Path:
        return self.folder / f"{PREFIX}{key.hex()[:24]}{SUFFIX}"

    def load(self, key: bytes) -> CodeType | None:
        """The code stored under `key`, or None (missing, another key or Python, damaged)."""
        header = MAGIC_NUMBER + key
        path = self._path(key)
        try:
            data = path.read_bytes()
            if not data.startswith(header):
                return None
            code = marshal.loads(data[len(header):])
        except FileNotFoundError:
            return None  # the first start of this program
        except (OSError, ValueError, EOFError, TypeError) as e:
            logger.warning("compiled program %s not used, compiling again: %s", path, e)
            return None
        if not isinstance(code, CodeType):
            logger.warning("compiled program %s not used, compiling again: not a code object", path)
            return None
        return code

    def store(self, key: bytes, code: CodeType) -> None:
        """Write `code` under `key` (atomically) and drop the files of older programs; a folder
        that cannot be written is left alone."""
        path = self._path(key)
        tmp = path.with_suffix(".tmp")
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            tmp.write_bytes(MAGIC_NUMBER + key + marshal.dumps(code))
            os.replace(tmp, path)
            for old in self.folder.glob(f"{PREFIX}*{SUFFIX}"):
                if old != path:
                    old.unlink(missing_ok=True)
        except OSError as e:  # each start compiles then: slower, never wrong
            logger.warning("compiled program not kept in %s: %s", self.folder, e)
            with contextlib.suppress(OSError):
                tmp.unlink(missing_ok=True)
