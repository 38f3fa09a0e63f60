"""A consistent copy of an SQLite file while the station writes it (the journal, the alarm states),
with SQLite's online backup API, for `main.py archive backup`.

The copy goes in steps of `pages` pages with a short pause between them, so the disk is shared
with the writer. A paged backup restarts from the first page whenever another connection commits
between two steps: at a journal's rate of commits a large file would never finish. So the copy
holds one read transaction from its first step to its last: it copies the file as it was at
that moment (every record committed before the backup began, none half written), and in WAL
mode a reader never blocks the writer, whose commits meanwhile go to the WAL (which can only be
checkpointed past the copy's moment once the copy ends: it grows by what is written meanwhile).
"""

from __future__ import annotations

import sqlite3
import time
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import quote

PAGES = 256  # pages per step: 1 MB at SQLite's default page size
PAUSE = 0.005  # seconds between two steps


@dataclass(frozen=True)
class Copied:
    pages: int  # the source's pages at the copy's moment
    steps: int
    seconds: float


def copy_database(source: Path, dest: Path, *, pages: int = PAGES, pause: float = PAUSE) -> Copied:
    """Copy the SQLite database `source` into a new file `dest`, consistent as of the call;
    sqlite3.Error names what failed."""
    started = time.monotonic()
    src = sqlite3.connect(f"file:{quote(str(source.resolve()))}?mode=ro", uri=True, isolation_level=None)
    try:
        src.execute("BEGIN")
        src.execute("SELECT count(*) FROM sqlite_master").fetchone()  # the read transaction starts here
        total = steps = 0

        def step(_status: int, remaining: int, count: int) -> None:
            nonlocal total, steps
            total, steps = count, steps + 1
            if remaining:
                time.sleep(pause)

        dst = sqlite3.connect(dest)
        try:
            src.backup(dst, pages=pages, progress=step)
        finally:
            dst.close()
    finally:
        src.close()
    return Copied(total, steps, time.monotonic() - started)
