"""The station's log: one configuration for every command of `main.py`, so a fault that code
catches and carries on from (`logger.exception`, a logger per module) reaches a person.

A running station (the workstation or `--no-gui`) writes a rotating log file in its folder
(`log/station.log`, 5 files of 5 MB at most: a log that cannot fill the disk the archive needs);
every command also logs to stderr at `--log-level` (default WARNING). Uncaught exceptions of the
main thread and of any other thread are logged with their traceback, so none reaches the console
without a log record beside it. When stderr is systemd's journal (a service: `JOURNAL_STREAM`
names it), each line carries its syslog priority instead of a time (the journal keeps its own),
so `journalctl -p warning` finds the station's warnings and errors.
"""

from __future__ import annotations

import logging
import logging.handlers
import os
import sys
import threading
from pathlib import Path

LOG_DIR = "log"
LOG_FILE = "station.log"
MAX_BYTES = 5 * 1024 * 1024
BACKUPS = 4
LEVELS = ("DEBUG", "INFO", "WARNING", "ERROR", "CRITICAL")
FORMAT = "%(asctime)s %(levelname)s %(threadName)s %(name)s: %(message)s"
JOURNAL_FORMAT = "%(levelname)s %(threadName)s %(name)s: %(message)s"
# libraries that log every request they serve at INFO (asyncua: each Read, Browse and Publish of
# every client): a line per request of every console fills the file and costs the server a record
# each; their warnings stay, their INFO only with DEBUG
CHATTY = ("asyncua",)
PRIORITIES = {logging.DEBUG: 7, logging.INFO: 6, logging.WARNING: 4, logging.ERROR: 3, logging.CRITICAL: 2}

logger = logging.getLogger(__name__)
_file_handler: logging.Handler | None = None


def configure(level: str = "WARNING") -> None:
    """Log to stderr at `level`; uncaught exceptions of every thread are logged; the CHATTY
    libraries' INFO only at DEBUG."""
    root = logging.getLogger()
    root.setLevel(logging.DEBUG if level == "DEBUG" else logging.INFO)
    for handler in [h for h in root.handlers if getattr(h, "_netplc", False)]:
        root.removeHandler(handler)
    console = logging.StreamHandler(sys.stderr)
    console.setLevel(level)
    console.setFormatter(_JournalFormatter(JOURNAL_FORMAT) if _to_journal() else logging.Formatter(FORMAT))
    console._netplc = True  # type: ignore[attr-defined]
    root.addHandler(console)
    for name in CHATTY:
        logging.getLogger(name).setLevel(logging.DEBUG if level == "DEBUG" else logging.WARNING)
    sys.excepthook = _uncaught
    threading.excepthook = _uncaught_in_thread


class _JournalFormatter(logging.Formatter):
    """Every line (a traceback's too) prefixed with the record's syslog priority, "<4>" for a
    warning: the journal reads it (SyslogLevelPrefix=, on by default) and strips it."""

    def format(self, record: logging.LogRecord) -> str:
        prefix = f"<{PRIORITIES.get(record.levelno, 6)}>"
        return "\n".join(prefix + line for line in super().format(record).splitlines())


def _to_journal() -> bool:
    """stderr is systemd's journal: JOURNAL_STREAM is the device and inode of that very stream (a
    service's child writing to a pipe or a file inherits the variable but not the stream)."""
    try:
        info = os.fstat(sys.stderr.fileno())
    except (OSError, ValueError, AttributeError):  # no log: no file behind stderr (a test's capture)
        return False
    return os.environ.get("JOURNAL_STREAM") == f"{info.st_dev}:{info.st_ino}"


def to_station_folder(folder: Path, level: str = "INFO") -> Path | None:
    """Also log into `folder/log/station.log` (rotating), at `level` or INFO, whichever is lower.
    A folder where no log can be written is said on stderr; the station runs on without the file."""
    global _file_handler
    root = logging.getLogger()
    path = Path(folder) / LOG_DIR / LOG_FILE
    try:
        path.parent.mkdir(exist_ok=True)
        handler = logging.handlers.RotatingFileHandler(path, maxBytes=MAX_BYTES, backupCount=BACKUPS,
                                                       encoding="utf-8")
    except OSError as e:
        logger.warning("no log file in %s: %s", path.parent, e.strerror or e)
        return None
    handler.setLevel(min(logging.getLevelName(level), logging.INFO))
    handler.setFormatter(logging.Formatter(FORMAT))
    handler._netplc = True  # type: ignore[attr-defined]
    if _file_handler is not None:
        root.removeHandler(_file_handler)
        _file_handler.close()
    root.addHandler(handler)
    _file_handler = handler
    return path


def _uncaught(kind: type[BaseException], value: BaseException, tb: object) -> None:
    if issubclass(kind, KeyboardInterrupt):
        sys.__excepthook__(kind, value, tb)  # type: ignore[arg-type]
        return
    logger.critical("uncaught exception", exc_info=(kind, value, tb))  # type: ignore[arg-type]


def _uncaught_in_thread(args: threading.ExceptHookArgs) -> None:
    if args.exc_type is SystemExit:
        return
    name = args.thread.name if args.thread is not None else "?"
    logger.critical("uncaught exception in thread %s", name,
                    exc_info=(args.exc_type, args.exc_value, args.exc_traceback))  # type: ignore[arg-type]
