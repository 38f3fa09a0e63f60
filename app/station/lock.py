"""One station per folder: a running station holds `station.lock` in its folder.

Two stations on one folder would write one journal, one retentive save and one alarm state file
from two processes, and a restore over a running station would swap its files under it. So the
runtime takes an exclusive lock on `station.lock` before it opens anything and keeps it until it
has stopped; `main.py archive restore` takes the same lock while it writes. The lock is the
kernel's (flock on POSIX, a locked byte on Windows): it goes with the process, so a station killed
with SIGKILL or a power cut leaves no stale lock behind, only the file, which names the pid that
held it last.
"""

from __future__ import annotations

import os
from pathlib import Path

if os.name == "nt":  # not run by the suite (Linux); here so that a station starts on Windows too
    import msvcrt

    def _lock(fd: int) -> bool:
        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)  # the first byte; another process cannot read it
        except OSError:
            return False
        return True

    def _holder(fd: int) -> str:
        return ""

    def _mark(fd: int) -> None:
        pass
else:
    import fcntl

    def _lock(fd: int) -> bool:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        return True

    def _holder(fd: int) -> str:
        return os.pread(fd, 32, 0).decode("ascii", "replace").strip()

    def _mark(fd: int) -> None:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)

LOCK_FILE = "station.lock"


class StationRunning(Exception):
    """A station runs in that folder: a second start on it, or a restore over it, is refused."""

    def __init__(self, folder: Path, pid: str) -> None:
        self.folder, self.pid = folder, pid
        super().__init__(f"{folder}: a station is running in this folder (pid {pid or '?'}, holding "
                         f"{LOCK_FILE}): stop it first")


class StationLock:
    """The exclusive lock of a station folder: `acquire`, then `release` (or a `with` block)."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self.path = self.folder / LOCK_FILE
        self._fd: int | None = None

    def acquire(self) -> None:
        """Take the lock and write our pid into the file; StationRunning when another holder has
        it, OSError when the file cannot be made (a read-only folder)."""
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        held = False
        try:
            if not _lock(fd):
                raise StationRunning(self.folder, _holder(fd))
            _mark(fd)
            held = True
        finally:
            if not held:  # whatever ended it: the file is not left open
                os.close(fd)
        self._fd = fd

    def release(self) -> None:
        """Give the lock up (closing the file does); safe to call twice."""
        fd, self._fd = self._fd, None
        if fd is not None:
            os.close(fd)

    def __enter__(self) -> StationLock:
        self.acquire()
        return self

    def __exit__(self, *_exc: object) -> None:
        self.release()
