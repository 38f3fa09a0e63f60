"""The Program view as a window: from the workstation's Station -> Program (the local runtime, with
writes, forcing and single scans) or from `main.py monitor STATION_OR_HOST:PORT` (a running station
over its Modbus server: read-only, since Modbus has no users; see source.py)."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

from PySide6.QtGui import QCloseEvent
from PySide6.QtWidgets import QApplication, QMainWindow, QWidget

from app.gui.monitor.source import LocalSource, RemoteSource, Source
from app.gui.monitor.view import ProgramMonitor
from app.gui.style import apply_style
from app.station.config import load_station
from app.station.load import load
from app.station.runtime import Runtime
from netplc.problems import Problems

SIZE = (1366, 768)


class ProgramWindow(QMainWindow):
    def __init__(self, source: Source, user: Callable[[], str], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.source = source
        self.setWindowTitle(f"Program — {source.title}" + ("" if source.acting else " (read-only)"))
        self.monitor = ProgramMonitor(source, user)
        self.setCentralWidget(self.monitor)
        self.resize(*SIZE)

    def closeEvent(self, event: QCloseEvent) -> None:
        self.monitor.timer.stop()
        self.source.close()
        super().closeEvent(event)


def open_local(runtime: Runtime, user: Callable[[], str]) -> ProgramWindow:
    window = ProgramWindow(LocalSource(runtime), user)
    window.show()
    return window


def remote_source(target: str) -> RemoteSource:
    """A station folder or station.toml (its program, symbols and Modbus server), or HOST:PORT
    (a bare watch table); Problems names what is wrong."""
    if Path(target).exists():
        station = load_station(target)
        server = station.modbus_server
        if not server.enabled:
            raise Problems([f"{station.path}: modbus_server.enabled: false: the station serves no Modbus "
                            "to monitor it over"])
        loaded = load(station)
        return RemoteSource(server.host, server.port, unit=server.unit or 1, program=loaded.program,
                            symbols=loaded.symbols, tags=loaded.tags.by_name)
    host, sep, port = target.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise Problems([f"{target}: neither a station folder nor HOST:PORT"])
    return RemoteSource(host, int(port))


def run_monitor(target: str) -> int:
    """`python main.py monitor STATION_OR_HOST:PORT`: read-only, so nobody acts through it."""
    app = QApplication.instance() or QApplication(sys.argv[:1])
    apply_style(app)  # type: ignore[arg-type]
    try:
        source = remote_source(target)
    except Problems as e:
        print("\n".join(e.problems), file=sys.stderr)
        return 2
    window = ProgramWindow(source, lambda: "")
    window.show()
    return app.exec()
