"""Retentive memory: what a CPU-165 keeps through a power cut, kept here through a restart.

That is all data memory, the I/O bits 03000-03477, and the timer and counter current values
(docs/architecture.md section 3). A save is written to a temporary file, fsynced and renamed over the current
one, whose last good version is kept as the previous save; a crash at any moment leaves at least
one complete save. Each save carries a CRC, so a damaged file is recognised and the previous one
used instead. While the engine scans, a save's state is taken by the engine thread between two
scans (a queued job, as writes are), so memory and the hidden timer and counter values are of the
same moment; once the scan thread has stopped, the memory is read as it was left.
"""

from __future__ import annotations

import json
import os
import struct
import threading
import time
import zlib
from dataclasses import dataclass
from pathlib import Path

from netplc.address import DATA_SIZE, IO_BITS, RETAIN_BITS
from netplc.engine import Engine
from netplc.memory import Memory, Snapshot
from netplc.records import Record, RecordSink
from netplc.timers import held

MAGIC = b"NPLCRETN"
VERSION = 1
HEADER = struct.Struct("<8sHII")  # magic, version, crc32 of the payload, payload length
SOURCE = "retain"
CAPTURE_WAIT = 1.0  # seconds a save waits for the engine thread to take the state (3 ticks if longer)
BITS = slice(RETAIN_BITS.start, RETAIN_BITS.stop)


class SaveError(ValueError):
    """A save file that cannot be used (missing, truncated, damaged, another format)."""


@dataclass(frozen=True)
class Saved:
    """The retentive state as read back from a save."""

    bits: bytes  # I/O bits 03000-03477, one per byte
    data: bytes  # all data memory
    tim: dict[int, float]
    ctr: dict[int, int]
    wall: float  # wall clock of the scan that was saved


class Retainer:
    def __init__(self, path: str | Path, engine: Engine, sink: RecordSink | None = None) -> None:
        self.path = Path(path)
        self.previous = self.path.with_name(self.path.name + ".prev")
        self._tmp = self.path.with_name(self.path.name + ".tmp")
        self.engine = engine
        self.sink = sink if sink is not None else engine.sink
        self.saves = 0
        self.last_error = ""
        self._current_good = False  # the current file is ours and complete: it may become .prev
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # --- restore -------------------------------------------------------------------------------

    def restore(self) -> str:
        """Load the newest good save into the engine; call it before the scan thread starts.

        Returns "current", "previous" or "zeroes" and journals which, and why, as a 'system' record.
        """
        problems: list[str] = []
        for used, path in (("current", self.path), ("previous", self.previous)):
            try:
                saved = read_save(path)
            except SaveError as e:
                problems.append(f"{used} save {e}")
                continue
            self._apply(saved)
            self._current_good = used == "current"
            why = f" ({'; '.join(problems)})" if problems else ""
            self._journal(f"retentive memory restored from the {used} save {path.name}{why}")
            return used
        self._apply(Saved(bytes(len(RETAIN_BITS)), bytes(DATA_SIZE), {}, {}, 0.0))
        self._journal(f"retentive memory starts from zeroes ({'; '.join(problems)})")
        return "zeroes"

    def _apply(self, saved: Saved) -> None:
        engine = self.engine
        mem = engine.mem
        mem.bits[BITS] = saved.bits
        mem.data[:] = saved.data
        engine.restore_values(saved.tim, saved.ctr)
        # Publish at once, so that a save before the first scan keeps what was restored.
        engine.snapshot = mem.snapshot(engine.scan_counter, engine.now, engine.wall_time(), engine.state_text)

    def _journal(self, text: str) -> None:
        self.sink.put(Record(self.engine.wall_time(), "system", source=SOURCE, text=text))

    # --- save ----------------------------------------------------------------------------------

    def save(self, *, live: bool = False) -> None:
        """Write the retentive state; OSError if the disk refuses. `live` while the scan thread
        runs (the state is then taken between two scans), else the memory is read as it is."""
        engine = self.engine
        snap, (tim, ctr) = self._capture() if live else (engine.snapshot, engine.held_values())
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

    def _capture(self) -> tuple[Snapshot, tuple[dict[int, float], dict[int, int]]]:
        """Memory and timer/counter values of one moment, taken by the engine thread at the start of
        its next scan; read directly if no scan comes (the scan thread stopped meanwhile)."""
        engine = self.engine
        taken: list[tuple[Snapshot, list[float], list[int]]] = []
        done = threading.Event()

        def take(mem: Memory) -> None:  # copies only: the scan it delays stays short
            taken.append((mem.snapshot(engine.scan_counter, engine.now, engine.wall_time()),
                          engine.tim_ticks.copy(), engine.ctr_values.copy()))
            done.set()

        engine.post(take)
        if done.wait(max(CAPTURE_WAIT, 3 * engine.tick)):
            snap, tim, ctr = taken[0]
            return snap, held(tim, ctr)
        return engine.snapshot, engine.held_values()

    def _save_reporting(self, live: bool = False) -> None:
        try:
            self.save(live=live)
        except OSError as e:
            if not self.last_error:
                self._journal(f"retentive memory could not be saved: {e}")
            self.last_error = str(e)
        else:
            if self.last_error:
                self.last_error = ""
                self._journal("retentive memory is being saved again")

    # --- background ----------------------------------------------------------------------------

    def start(self, interval: float = 1.0) -> None:
        self._stop.clear()
        self._thread = threading.Thread(target=self._loop, args=(interval,), name="retain", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop the periodic saves and save once more (call it after the scan thread stopped)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        self._save_reporting()

    def _loop(self, interval: float) -> None:
        """Save on a fixed cadence: a slow fsync must not push every later save back as well."""
        due = time.monotonic() + interval
        while not self._stop.wait(max(0.0, due - time.monotonic())):
            self._save_reporting(live=True)
            due = max(due + interval, time.monotonic())


def read_save(path: Path) -> Saved:
    try:
        blob = path.read_bytes()
    except FileNotFoundError:
        raise SaveError("is missing") from None
    except OSError as e:
        raise SaveError(f"cannot be read: {e.strerror}") from None
    if len(blob) < HEADER.size:
        raise SaveError("is truncated")
    magic, version, crc, length = HEADER.unpack_from(blob)
    if magic != MAGIC or version != VERSION:
        raise SaveError("is not a retentive memory save of this version")
    payload = blob[HEADER.size:]
    if len(payload) != length or zlib.crc32(payload) != crc:
        raise SaveError("is damaged (length or checksum wrong)")
    nbits = len(RETAIN_BITS)
    try:
        meta = json.loads(payload[nbits + DATA_SIZE:])
        tim = {int(k): float(v) for k, v in meta["tim"].items()}
        ctr = {int(k): int(v) for k, v in meta["ctr"].items()}
        wall = float(meta["wall"])
        if any(not 0 <= c < IO_BITS for c in (*tim, *ctr)):
            raise ValueError("a timer or counter address outside the I/O bits")
    except (ValueError, KeyError, TypeError, AttributeError) as e:
        raise SaveError(f"has unreadable timer and counter values: {e}") from None
    return Saved(payload[:nbits], payload[nbits:nbits + DATA_SIZE], tim, ctr, wall)


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
