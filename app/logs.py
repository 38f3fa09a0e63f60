"""The station's log: one configuration for every command of `main.py`, so a fault that code
catches and carries on from (`logger.exception`, a logger per module) reaches a person.

A running station (the workstation or `--no-gui`) writes a rotating log file in its folder
(`log/station.log`, 5 files of 5 MB at most: a log that cannot fill the disk the archive needs);
every command also logs to stderr at `--log-level` (default WARNING). Uncaught exceptions of the
main thread and of any other thread are logged with their traceback, so none reaches the console
without a log record beside it.
"""

from __future__ import annotations

import logging
import logging.handlers
import sys
import threading
from pathlib import Path

LOG_DIR = "log"
LOG_FILE = "station.log"
MAX_BYTES = 5 * 1024 * 1024
BACKUPS = 4
LEVELS = ("DEBUG", "INFO", "WARNING", "ERROR", "CRITICAL")
FORMAT = "%(asctime)s %(levelname)s %(threadName)s %(name)s: %(message)s"

logger = logging.getLogger(__name__)
_file_handler: logging.Handler | None = None


def configure(level: str = "WARNING") -> None:
    """Log to stderr at `level`; uncaught exceptions of every thread are logged."""
    root = logging.getLogger()
    root.setLevel(logging.DEBUG if level == "DEBUG" else logging.INFO)
    for handler in [h for h in root.handlers if getattr(h, "_netplc", False)]:
        root.removeHandler(handler)
    console = logging.StreamHandler(sys.stderr)
    console.setLevel(level)
    console.setFormatter(logging.Formatter(FORMAT))
    console._netplc = True  # type: ignore[attr-defined]
    root.addHandler(console)
    sys.excepthook = _uncaught
    threading.excepthook = _uncaught_in_thread


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
