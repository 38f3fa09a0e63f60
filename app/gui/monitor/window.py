"""The Program view as a window: from the workstation's Station -> Program (the local runtime, with
writes, forcing and single scans), or from `main.py monitor`: a running station over its OPC UA
endpoint as a user of that station (`opc.tcp://...`, after the login dialog: login.py), or over its
Modbus server (`STATION_OR_HOST:PORT`: read-only, since Modbus has no users; see source.py)."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

from PySide6.QtGui import QCloseEvent
from PySide6.QtWidgets import QMainWindow, QWidget

from app.gui.application import application
from app.gui.monitor.source import LocalSource, OpcUaSource, RemoteSource, Source
from app.gui.monitor.view import ProgramMonitor
from app.scada.tag import Tag
from app.station.config import load_station
from app.station.load import load
from app.station.runtime import Runtime
from netplc.problems import Problems
from netplc.program import Program, parse_file

SIZE = (1366, 768)


class ProgramWindow(QMainWindow):
    def __init__(self, source: Source, user: Callable[[], str], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.source = source
        self.setWindowTitle(self.tr("Program — {0}").format(source.title)
                            + ("" if source.acting else self.tr(" (read-only)")))
        self.monitor = ProgramMonitor(source, user)
        self.setCentralWidget(self.monitor)
        self.monitor.said.connect(self.statusBar().showMessage)
        self.resize(*SIZE)

    def closeEvent(self, event: QCloseEvent) -> None:
        self.monitor.timer.stop()
        self.source.close()
        super().closeEvent(event)


def open_local(runtime: Runtime, user: Callable[[], str]) -> ProgramWindow:
    window = ProgramWindow(LocalSource(runtime), user)
    window.show()
    return window


Listing = tuple[Program, dict[str, int], dict[str, Tag]]  # the program, its symbols, the tags by name


def listing(path: str) -> Listing:
    """What the monitor lists: a station folder or station.toml (its program, symbols and tags), or
    a program file (PROGRAM.stl); Problems names what is wrong."""
    if Path(path).is_dir() or path.endswith(".toml"):
        loaded = load(load_station(path))
        return loaded.program, loaded.symbols, loaded.tags.by_name
    if not Path(path).is_file():
        raise Problems([f"{path}: neither a program file nor a station folder"])
    return parse_file(path), {}, {}


def remote_source(target: str, program: str | None = None) -> RemoteSource:
    """A station folder or station.toml (its program, symbols and Modbus server), or HOST:PORT
    (a bare watch table, or `program`'s listing); Problems names what is wrong."""
    if Path(target).exists():
        station = load_station(target)
        server = station.modbus_server
        if not server.enabled:
            raise Problems([f"{station.path}: modbus_server.enabled: false: the station serves no Modbus "
                            "to monitor it over"])
        if server.serial is not None:
            raise Problems([f"{station.path}: modbus_server.transport: the station serves Modbus RTU on "
                            f"{server.serial.device}, not TCP: monitor it over OPC UA (opc.tcp://...)"])
        listed, symbols, tags = listing(program or target)
        return RemoteSource(server.host, server.port, unit=server.unit or 1, program=listed, symbols=symbols,
                            tags=tags)
    host, sep, port = target.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise Problems([f"{target}: neither an opc.tcp:// URL, a station folder nor HOST:PORT"])
    if program is None:
        return RemoteSource(host, int(port))
    listed, symbols, tags = listing(program)
    return RemoteSource(host, int(port), program=listed, symbols=symbols, tags=tags)


def run_monitor(target: str, program: str | None = None, user: str | None = None,
                partner: str = "") -> int:
    """`python main.py monitor TARGET [--program P] [--user NAME] [--partner URL]`: over OPC UA as a
    user of the station (the login dialog; with --user and stdin not a terminal, the password is its
    first line; with --partner it follows the pair's primary), over Modbus read-only. Exit 2 with
    the reason when it cannot start, 1 when the login is cancelled."""
    app = application()
    try:
        if target.startswith("opc.tcp://"):
            source: Source | None = station_source(target, program, user, partner)
            if source is None:
                return 1
        else:
            source = remote_source(target, program)
    except Problems as e:
        print("\n".join(e.problems), file=sys.stderr)
        return 2
    user = source.client.user if isinstance(source, OpcUaSource) else ""  # the station's user, or nobody
    window = ProgramWindow(source, lambda: user)
    window.show()
    return app.exec()


def station_source(url: str, program: str | None = None, user: str | None = None,
                   partner: str = "") -> OpcUaSource | None:
    """A station over OPC UA, logged in through the login dialog; None when it was cancelled.
    `partner`: the other station of its hot-standby pair, followed to when it leads."""
    from app.gui.monitor.login import logged_in
    from app.publish.client import StationClient  # OPC UA loaded only for a station over OPC UA

    listed = listing(program) if program else None
    password = sys.stdin.readline().rstrip("\r\n") if user and not sys.stdin.isatty() else None
    client = StationClient(url, partner=partner)
    if not logged_in(client, user, password):
        return None
    if listed is None:
        return OpcUaSource(client)
    return OpcUaSource(client, program=listed[0], symbols=listed[1], tags=listed[2])
