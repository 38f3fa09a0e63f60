"""The alarms' states on disk, so that a restart changes nothing an operator must act on.

What was unacknowledged stays unacknowledged, a shelving keeps its end time, an alarm out of
service stays out, and a condition that was active is known to be, so it raises no second alarm
(netplc/tags/alarms.py). The file is JSON (`alarms.json` next to the archive), written as
retentive memory is: to a temporary file, fsynced, renamed over the old one, so a crash at any
moment leaves either the old or the new file, whole.

`update` is called on the engine thread with the states that changed; it only merges them and
wakes a writer thread of its own, so a flood of transitions never waits for a disk. `close`
writes what is left.
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from netplc.records import NullSink, Record, RecordSink
from registrar.retain import _fsync_dir

SOURCE = "alarms"
VERSION = 1


class AlarmStateFile:
    def __init__(self, path: str | Path, sink: RecordSink | None = None,
                 wallclock: Callable[[], float] = time.time) -> None:
        self.path = Path(path)
        self._tmp = self.path.with_name(self.path.name + ".tmp")
        self.sink = sink or NullSink()
        self.wallclock = wallclock
        self.states: dict[str, dict[str, Any]] = {}
        self.saves = 0
        self.last_error = ""
        self._lock = threading.Lock()  # guards states and _dirty
        self._write_lock = threading.Lock()  # one write at a time (writer thread or close)
        self._dirty = False
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def load(self) -> dict[str, dict[str, Any]]:
        """The states of the last run; none (all normal) when there is no file or it cannot be
        used, which a 'system' record explains."""
        try:
            doc = json.loads(self.path.read_text(encoding="utf-8"))
            if doc.get("version") != VERSION or not isinstance(doc.get("alarms"), dict):
                raise ValueError("not an alarm state file of this version")
            states = {str(k): dict(v) for k, v in doc["alarms"].items()}
        except FileNotFoundError:
            return {}
        except (OSError, ValueError, TypeError, AttributeError) as e:
            self._journal(f"alarm states not restored from {self.path.name}: {e}; every alarm starts normal")
            return {}
        with self._lock:
            self.states = states
        self._journal(f"alarm states restored from {self.path.name}: {len(states)} alarm(s)")
        return states

    def update(self, changes: dict[str, dict[str, Any]]) -> None:
        """Merge the states that changed; the writer thread saves them soon (at once if none runs)."""
        with self._lock:
            self.states.update(changes)
            self._dirty = True
        if self._thread is None:
            self.flush()
        else:
            self._wake.set()

    def flush(self) -> None:
        """Write now if anything changed since the last save; a failure is journaled once."""
        with self._write_lock:
            with self._lock:
                if not self._dirty:
                    return
                self._dirty = False
                doc = {"version": VERSION, "saved": self.wallclock(), "alarms": dict(self.states)}
            try:
                self._write(json.dumps(doc, ensure_ascii=False, separators=(",", ":")))
            except OSError as e:
                with self._lock:
                    self._dirty = True
                if not self.last_error:
                    self._journal(f"alarm states could not be saved: {e}")
                self.last_error = str(e)
                return
            if self.last_error:
                self.last_error = ""
                self._journal("alarm states are being saved again")

    def _write(self, text: str) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with open(self._tmp, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(self._tmp, self.path)
        _fsync_dir(self.path.parent)
        self.saves += 1

    def start(self) -> None:
        self._stop.clear()
        self._thread = threading.Thread(target=self._loop, name="alarm-state", daemon=True)
        self._thread.start()

    def close(self) -> None:
        """Stop the writer and write what is left."""
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        self.flush()

    def _loop(self) -> None:
        while not self._stop.is_set():
            self._wake.wait(1.0)
            self._wake.clear()
            self.flush()

    def _journal(self, text: str) -> None:
        self.sink.put(Record(self.wallclock(), "system", source=SOURCE, text=text))
