"""The alarms' states on disk, so that a restart changes nothing an operator must act on.

What was unacknowledged stays unacknowledged, a shelving keeps its end time, an alarm out of
service stays out, and a condition that was active is known to be, so it raises no second alarm
(app/scada/alarms.py). The states live in a small SQLite file of their own next to the archive
(`alarms.sqlite`, one row per alarm that ever changed), so that a change costs a row, not a copy
of every alarm: a flood of 10,000 transitions writes 10,000 small rows, in a few transactions,
and a crash at any moment leaves the last committed transaction whole.

`update` is called on the engine thread with the states that changed; it only merges them into
what is pending and wakes a writer thread of its own, so the scan never waits for a disk.
`close` writes what is left.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import sqlite3
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from app.scada.words import ENGLISH, Words, words
from netplc.records import NullSink, Record, RecordSink

logger = logging.getLogger(__name__)
SOURCE = "alarms"
TABLE_SQL = "CREATE TABLE IF NOT EXISTS alarm_state (alarm TEXT PRIMARY KEY, state TEXT NOT NULL)"
FLUSH_EVERY = 0.1  # seconds the writer waits for more changes before it writes


class AlarmStateFile:
    def __init__(self, path: str | Path, sink: RecordSink | None = None,
                 wallclock: Callable[[], float] = time.time, say: Words | None = None) -> None:
        self.path = Path(path)
        self.say = say or words()  # its records in the station's language (app/scada/words.py)
        self.sink = sink or NullSink()
        self.wallclock = wallclock
        self.saves = 0  # transactions committed
        self.rows = 0  # rows written
        self.last_error = ""
        self._pending: dict[str, dict[str, Any]] = {}
        self._lock = threading.Lock()  # guards _pending
        self._write_lock = threading.Lock()  # one writer at a time (the thread, or flush/close)
        self._con: sqlite3.Connection | None = None
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def load(self) -> dict[str, dict[str, Any]]:
        """The states of the last run; none (every alarm normal) without a file. A file that
        cannot be read is moved aside as `.damaged` and a 'system' record says so."""
        try:
            con = self._open()
            states = {alarm: json.loads(text) for alarm, text in
                      con.execute("SELECT alarm, state FROM alarm_state")}
        except (sqlite3.Error, ValueError) as e:
            self._close_con()
            damaged = self.path.with_name(self.path.name + ".damaged")
            with contextlib.suppress(OSError):  # nothing to move aside
                os.replace(self.path, damaged)
            said = {"file": self.path.name, "error": e, "damaged": damaged.name}
            logger.warning("%s", ENGLISH("states not restored", **said))
            self._journal("states not restored", **said)
            return {}
        if states:
            self._journal("states restored", file=self.path.name, n=len(states))
        return states

    def _open(self) -> sqlite3.Connection:
        if self._con is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            con = sqlite3.connect(self.path, isolation_level=None, check_same_thread=False)
            try:
                con.execute("PRAGMA journal_mode=WAL")
                con.execute("PRAGMA synchronous=FULL")  # an acknowledgement is kept once written
                con.execute(TABLE_SQL)
            except sqlite3.Error:
                con.close()
                raise
            self._con = con
        return self._con

    def _close_con(self) -> None:
        if self._con is not None:
            self._con.close()
            self._con = None

    def update(self, changes: dict[str, dict[str, Any]]) -> None:
        """Merge the states that changed; the writer thread saves them soon (at once if none runs)."""
        with self._lock:
            self._pending.update(changes)
        if self._thread is None:
            self.flush()
        else:
            self._wake.set()

    def flush(self) -> None:
        """Write what is pending in one transaction; a failure keeps it and is journaled once."""
        with self._write_lock:
            with self._lock:
                pending, self._pending = self._pending, {}
            if not pending:
                return
            try:
                con = self._open()
                con.execute("BEGIN IMMEDIATE")
                rows = [(alarm, json.dumps(state, ensure_ascii=False)) for alarm, state in pending.items()]
                con.executemany("INSERT OR REPLACE INTO alarm_state VALUES (?, ?)", rows)
                con.execute("COMMIT")
            except (sqlite3.Error, OSError) as e:
                if self._con is not None and self._con.in_transaction:
                    self._con.execute("ROLLBACK")
                with self._lock:
                    self._pending = {**pending, **self._pending}
                if not self.last_error:
                    logger.warning("alarm states could not be saved to %s: %s; kept in memory and retried",
                                   self.path, e)
                    self._journal("states not saved", error=e)
                self.last_error = str(e)
                return
            self.saves += 1
            self.rows += len(pending)
            if self.last_error:
                self.last_error = ""
                self._journal("states saved again")

    def start(self) -> None:
        self._stop.clear()
        self._thread = threading.Thread(target=self._loop, name="alarm-state", daemon=True)
        self._thread.start()

    def close(self) -> None:
        """Stop the writer, write what is left and close the file."""
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        self.flush()
        with self._write_lock:
            self._close_con()

    def _loop(self) -> None:
        while not self._stop.is_set():
            self._wake.wait(1.0)
            if self._stop.wait(FLUSH_EVERY):  # gather a burst into one transaction
                return
            self._wake.clear()
            self.flush()

    def _journal(self, name: str, /, **values: object) -> None:
        self.sink.put(Record(self.wallclock(), "system", source=SOURCE, text=self.say(name, **values)))
