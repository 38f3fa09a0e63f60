"""A real archive file that a test can hold locked, to show that a view reads it off the GUI thread.

The station's archive is in WAL mode, where nothing a writer does blocks a reader. Switched back
to a rollback journal, a writer's EXCLUSIVE transaction does: every read waits for it (SQLite's
busy timeout, 5 s) and goes on as soon as the writer lets go. A view that read on the GUI thread
would freeze for as long as the lock is held.
"""

from __future__ import annotations

import sqlite3
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from netplc.records import Record
from registrar.store import Store


def archive_with(path: Path, texts: list[str], kind: str = "message") -> Path:
    """An archive at `path` holding today's records of `texts` (in that order), in rollback-journal mode."""
    store = Store(path)
    store.start()
    now = time.time()
    for i, text in enumerate(texts):
        store.put(Record(now + i * 0.001, kind, grp=1, type=1, text=text))
    store.close()
    con = sqlite3.connect(path)
    try:
        assert con.execute("PRAGMA journal_mode=DELETE").fetchone()[0] == "delete"
    finally:
        con.close()
    return path


@contextmanager
def held(path: Path) -> Iterator[None]:
    """The archive locked by a writer: every reader waits until the block ends."""
    con = sqlite3.connect(path, isolation_level=None)
    try:
        con.execute("BEGIN EXCLUSIVE")
        yield
        con.execute("ROLLBACK")
    finally:
        con.close()


class Ticks:
    """A 20 ms timer on the GUI thread: it counts only while that thread is free to run it."""

    def __init__(self) -> None:
        from PySide6.QtCore import QTimer

        self.count = 0
        self.timer = QTimer()
        self.timer.setInterval(20)
        self.timer.timeout.connect(self._tick)
        self.timer.start()

    def _tick(self) -> None:
        self.count += 1

    def stop(self) -> None:
        self.timer.stop()
