"""Retentive memory: what a CPU-165 keeps through a power cut, kept here through a restart.

That is all data memory, the I/O bits 03000-03477, and the timer and counter current values
(docs/architecture.md section 3). A save is written to a temporary file, fsynced and renamed over the current
one, whose last good version is kept as the previous save; a crash at any moment leaves at least
one complete save. Each save carries a CRC, so a damaged file is recognised and the previous one
used instead.

An acknowledged outside write survives a crash of the station: a writer is answered only once its
journal record is committed AND a save holding the memory of the scan that applied it is durable
(`after_save`, joined with the archive's commit by the runtime's `after_commit`). Saving before
answering was chosen over replaying, at start, the writes journaled after the last save: a replay
would need the journal to carry each write's raw bytes, in the exact order the engine applied them
among the program's own changes and the network's results, and a bug there would silently give
other memory than the plant had; a save is the state itself. It costs one small fsynced file per
scan at most, shared by every writer of that scan, written on the retainer's thread (the scan only
copies the timer and counter values), and a writer's answer comes one fsync later.

The state of a save is taken by an engine listener at the end of a scan, so memory (the published
snapshot) and the hidden timer and counter values are of the same moment; a save wanted while the
saver still writes the previous one is taken at the next scan's end and replaces any not yet
written, so saves never queue up behind a slow disk. Without writers the state is saved once a
`start` interval, for what the program changes itself; once the scan thread has stopped, the
memory is read as it was left. A save that fails still answers its writers (they were applied and
journaled, and holding them would make Modbus clients retry): the failure is journaled once and
shown, and a start that falls back to an older save says which writes may be lost.
"""

from __future__ import annotations

import json
import logging
import os
import struct
import threading
import time
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from app.scada.words import ENGLISH, Phrase, Phrases, Words, phrase, words
from netplc.address import DATA_SIZE, IO_BITS, RETAIN_BITS
from netplc.engine import Engine
from netplc.memory import Snapshot
from netplc.records import Record, RecordSink
from netplc.timers import held

MAGIC = b"NPLCRETN"
VERSION = 1
HEADER = struct.Struct("<8sHII")  # magic, version, crc32 of the payload, payload length
SOURCE = "retain"
CAPTURE_WAIT = 1.0  # seconds a wanted save waits for a scan to take the state (3 ticks if longer)
BITS = slice(RETAIN_BITS.start, RETAIN_BITS.stop)

logger = logging.getLogger(__name__)


class SaveError(ValueError):
    """A save file that cannot be used (missing, truncated, damaged, another format): English as
    an exception, in parts (the catalogue's `name` and `values`, app/scada/words.py) for the
    journal's language."""

    def __init__(self, name: str, /, **values: object) -> None:
        super().__init__(ENGLISH(name, **values))
        self.name = name
        self.values = values


@dataclass(frozen=True)
class Saved:
    """The retentive state as read back from a save."""

    bits: bytes  # I/O bits 03000-03477, one per byte
    data: bytes  # all data memory
    tim: dict[int, float]
    ctr: dict[int, int]
    wall: float  # wall clock of the scan that was saved


@dataclass
class _Taken:
    """The state of one moment, to be saved, and the writers waiting for it to be durable."""

    snap: Snapshot
    tim: list[float]
    ctr: list[int]
    waiters: list[Callable[[], None]]


class Retainer:
    def __init__(self, path: str | Path, engine: Engine, sink: RecordSink | None = None,
                 say: Words | None = None) -> None:
        self.path = Path(path)
        self.say = say or words()  # its records in the station's language (app/scada/words.py)
        _, (_, self._tmp), (_, self.previous) = save_files(self.path)
        self.engine = engine
        self.sink = sink if sink is not None else engine.sink
        self.saves = 0
        self.last_error = ""
        self._current_good = False  # the current file is ours and complete: it may become .prev
        self._lock = threading.Lock()  # one save at a time writes the files
        # between the engine listener, the writers' after_save and the saver thread:
        self._cond = threading.Condition()
        self._want = False  # a save is wanted: the next scan's end is taken
        self._asked = 0.0  # when it was first wanted (monotonic), for the wait on a scan
        self._waiting: list[Callable[[], None]] = []  # after_save callbacks no state was taken for
        self._taken: _Taken | None = None  # taken at a scan's end, not yet written
        self._stopping = False
        self._thread: threading.Thread | None = None
        self._unsubscribe: Callable[[], None] | None = None

    # --- restore -------------------------------------------------------------------------------

    def restore(self) -> str:
        """Load the newest good save into the engine; call it before the scan thread starts.

        Returns "current", "previous" or "zeroes" and journals which, and why, as a 'system' record;
        when a save was there but could not be used, also that acknowledged writes may be lost. A
        crash between a save's two renames (the current save moved to previous, the new one not yet
        in its place) leaves the newest save, complete and fsynced, as the temporary file: it is used,
        and becomes the current save.
        """
        problems: list[Phrase] = []  # "current save is missing"...
        for used, path in save_files(self.path):
            try:
                saved = read_save(path)
            except SaveError as e:
                if used != "written":  # it is there only when a crash came while a save was written
                    problems.append(phrase(f"{used} save problem", problem=phrase(e.name, **e.values)))
                continue
            self._apply(saved)
            why = phrase("retain why", problems=Phrases(problems)) if problems else ""
            if used == "written":  # a crash between a save's two renames: the newest save, complete
                self._journal("retain crash", file=path.name, why=why)
                self._promote()
                return "current"
            self._current_good = used == "current"
            said = {"used": phrase(f"save {used}"), "file": path.name, "why": why}
            if used == "previous":
                said["when"] = _when(saved.wall)
                logger.warning("%s", ENGLISH("retain lost after", **said))
                self._journal("retain lost after", **said)
            else:
                self._journal("retain restored", **said)
            return used
        self._apply(Saved(bytes(len(RETAIN_BITS)), bytes(DATA_SIZE), {}, {}, 0.0))
        name = "retain zeroes"
        if any(p.values["problem"].name != "save missing" for p in problems):  # type: ignore[attr-defined]
            name = "retain zeroes lost"
            logger.warning("%s", ENGLISH(name, problems=Phrases(problems)))
        self._journal(name, problems=Phrases(problems))
        return "zeroes"

    def _promote(self) -> None:
        """Make the save written at a crash the current one, so the next save keeps it as previous."""
        try:
            os.replace(self._tmp, self.path)
            _fsync_dir(self.path.parent)
        except OSError as e:  # the next save tries again; until then the file is used as it is
            logger.warning("retentive save %s not renamed to %s: %s", self._tmp, self.path, e)
            self._journal("retain not renamed", tmp=self._tmp.name, file=self.path.name, error=e)
        else:
            self._current_good = True

    def _apply(self, saved: Saved) -> None:
        engine = self.engine
        mem = engine.mem
        mem.bits[BITS] = saved.bits
        mem.data[:] = saved.data
        engine.restore_values(saved.tim, saved.ctr)
        # Publish at once, so that a save before the first scan keeps what was restored.
        engine.snapshot = mem.snapshot(engine.scan_counter, engine.now, engine.wall_time(), engine.state_text)

    def _journal(self, name: str, /, **values: object) -> None:
        self.sink.put(Record(self.engine.wall_time(), "system", source=SOURCE, text=self.say(name, **values)))

    # --- save ----------------------------------------------------------------------------------

    def after_save(self, callback: Callable[[], None]) -> None:
        """Call `callback()`, on the retainer's thread, once a save of the memory as the current scan
        leaves it is durable (or was tried and failed, which is journaled). The engine thread calls
        it while applying a scan's writes; every writer of the scan shares the one save. Thread-safe:
        from another thread, the save is of the end of a scan that ends after the call."""
        with self._cond:
            self._waiting.append(callback)
            self._ask()

    def _ask(self) -> None:
        """Want a save (with _cond held)."""
        if not self._want:
            self._want, self._asked = True, time.monotonic()

    def _on_scan(self, snapshot: Snapshot) -> None:
        """The engine listener: take the state at the end of this scan if a save is wanted. Copies
        of two lists only, so the scan stays short; the saver thread does the rest."""
        if not self._want:
            return
        engine = self.engine
        tim, ctr = engine.tim_ticks.copy(), engine.ctr_values.copy()
        with self._cond:
            self._want = False
            waiters, self._waiting = self._waiting, []
            if self._taken is not None:  # not yet written: this newer state replaces it
                waiters[:0] = self._taken.waiters
            self._taken = _Taken(snapshot, tim, ctr, waiters)
            self._cond.notify()

    def _as_left(self) -> _Taken:
        """The state as the engine left it, with every waiter (with _cond held): for a save no
        scan comes to take (the scan thread stopped)."""
        engine = self.engine
        waiters = (self._taken.waiters if self._taken is not None else []) + self._waiting
        self._taken, self._waiting, self._want = None, [], False
        return _Taken(engine.snapshot, engine.tim_ticks.copy(), engine.ctr_values.copy(), waiters)

    def save(self) -> None:
        """Write the retentive state as the engine holds it now; OSError if the disk refuses. Only
        while no scan runs: while the scan thread runs, the state is taken at the end of a scan
        (`after_save`, `start`)."""
        engine = self.engine
        self._write(engine.snapshot, *engine.held_values())

    def _write(self, snap: Snapshot, tim: dict[int, float], ctr: dict[int, int]) -> None:
        meta = json.dumps({"tim": {str(k): v for k, v in tim.items()},
                           "ctr": {str(k): v for k, v in ctr.items()},
                           "wall": snap.wall, "scan": snap.scan}).encode()
        payload = bytes(snap.bits[BITS]) + snap.data + meta
        blob = HEADER.pack(MAGIC, VERSION, zlib.crc32(payload), len(payload)) + payload
        with self._lock:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            with open(self._tmp, "wb") as f:
                f.write(blob)
                f.flush()
                os.fsync(f.fileno())
            if self._current_good and self.path.exists():
                os.replace(self.path, self.previous)
            os.replace(self._tmp, self.path)
            _fsync_dir(self.path.parent)
            self._current_good = True
            self.saves += 1

    def _save_reporting(self, taken: _Taken) -> None:
        """Save `taken`, journal a failure once and the recovery once, then answer its waiters."""
        try:
            self._write(taken.snap, *held(taken.tim, taken.ctr))
        except OSError as e:
            if not self.last_error:  # said once; the health strip shows it while it lasts
                logger.warning("retentive memory could not be saved to %s: %s", self.path, e)
                self._journal("retain not saved", error=e)
            self.last_error = str(e)
        else:
            if self.last_error:
                self.last_error = ""
                self._journal("retain saved again")
        for callback in taken.waiters:
            try:
                callback()
            except Exception as e:  # one waiter's bug must not leave the others unanswered
                logger.exception("a writer waiting for the retentive save failed")
                self._journal("retain waiter failed", error=repr(e))

    # --- background ----------------------------------------------------------------------------

    def start(self, interval: float = 1.0) -> None:
        """Take and write saves from now on: promptly for waiters, and every `interval` seconds."""
        with self._cond:
            self._stopping = False
        self._unsubscribe = self.engine.subscribe(self._on_scan, "retentive memory")
        self._thread = threading.Thread(target=self._loop, args=(interval,), name="retain", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop the saves and save once more, answering every waiter (call it after the scan
        thread stopped)."""
        if self._unsubscribe is not None:
            self._unsubscribe()
            self._unsubscribe = None
        with self._cond:
            self._stopping = True
            self._cond.notify()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        with self._cond:
            last = self._as_left()
        self._save_reporting(last)

    def _loop(self, interval: float) -> None:
        """Write each state as soon as a scan took it; ask for one every `interval` on a fixed
        cadence (a slow fsync must not push every later save back as well)."""
        wait = max(CAPTURE_WAIT, 3 * self.engine.tick)
        due = time.monotonic() + interval
        while True:
            with self._cond:
                while self._taken is None and not self._stopping:
                    now = time.monotonic()
                    if now >= due:
                        self._ask()
                    if self._want and now >= self._asked + wait:
                        break  # no scan took it: the scan thread has stopped
                    self._cond.wait((self._asked + wait if self._want else due) - now)
                if self._stopping:
                    return  # stop() saves the rest
                taken = self._taken if self._taken is not None else self._as_left()
                self._taken = None
            started = time.monotonic()
            self._save_reporting(taken)
            if started >= due:
                due = max(due + interval, time.monotonic())


def save_files(path: Path) -> tuple[tuple[str, Path], ...]:
    """The files of the save at `path`, in the order a restore tries them: the current save, the
    one written at a crash between a save's two renames, the previous save."""
    return (("current", path), ("written", path.with_name(path.name + ".tmp")),
            ("previous", path.with_name(path.name + ".prev")))


def newest_save(path: Path) -> bytes | None:
    """The save a restore would use now, as bytes (read while saves go on: each file is whole,
    written then renamed); None when there is none."""
    for _, file in save_files(path):
        try:
            blob = file.read_bytes()
            parse_save(blob)
        except (OSError, SaveError):  # no log: the next file is tried, as a restore does
            continue
        return blob
    return None


def read_save(path: Path) -> Saved:
    try:
        blob = path.read_bytes()
    except FileNotFoundError:
        raise SaveError("save missing") from None
    except OSError as e:
        raise SaveError("save unreadable", error=e.strerror) from None
    return parse_save(blob)


def parse_save(blob: bytes) -> Saved:
    if len(blob) < HEADER.size:
        raise SaveError("save truncated")
    magic, version, crc, length = HEADER.unpack_from(blob)
    if magic != MAGIC or version != VERSION:
        raise SaveError("save version")
    payload = blob[HEADER.size:]
    if len(payload) != length or zlib.crc32(payload) != crc:
        raise SaveError("save damaged")
    nbits = len(RETAIN_BITS)
    try:
        meta = json.loads(payload[nbits + DATA_SIZE:])
        tim = {int(k): float(v) for k, v in meta["tim"].items()}
        ctr = {int(k): int(v) for k, v in meta["ctr"].items()}
        wall = float(meta["wall"])
        if any(not 0 <= c < IO_BITS for c in (*tim, *ctr)):
            raise ValueError("a timer or counter address outside the I/O bits")
    except (ValueError, KeyError, TypeError, AttributeError) as e:
        raise SaveError("save counters", error=e) from None
    return Saved(payload[:nbits], payload[nbits:nbits + DATA_SIZE], tim, ctr, wall)


def _when(wall: float) -> str:
    """A save's wall-clock time as the journal's reader reads it (local time, to the millisecond)."""
    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(wall)) + f".{int(wall % 1 * 1000):03d}"


def _fsync_dir(directory: Path) -> None:
    """Make the renames themselves durable (POSIX); not possible on every platform."""
    flags = getattr(os, "O_DIRECTORY", None)
    if flags is None:
        return
    fd = os.open(directory, os.O_RDONLY | flags)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
