"""The workstation's status bar: NetPlc state, scan time, tick, node links, archive.

Each item is a small pill whose colour says at a glance whether it is well (green), needs
attention (amber) or is failing (red), with the figures beside it for whoever looks closer.
"""

from __future__ import annotations

from PySide6.QtCore import QT_TRANSLATE_NOOP, QCoreApplication
from PySide6.QtWidgets import QLabel, QStatusBar, QWidget

from app.station.runtime import RuntimeStatus

OK, WARN, BAD, IDLE = "ok", "warn", "bad", "idle"
UP, DOWN = "\u25cf", "\u25cb"  # filled and hollow circles
STARTUP_GRACE_MS = 3000  # links need a moment after start; do not cry "no link" before that


class Pill(QLabel):
    def __init__(self, text: str = "", parent: QWidget | None = None) -> None:
        super().__init__(text, parent)
        self.setObjectName("pill")
        self.set_level(IDLE)

    def set_level(self, level: str) -> None:
        if self.property("level") != level:
            self.setProperty("level", level)
            self.style().unpolish(self)
            self.style().polish(self)

    def show_value(self, text: str, level: str, tip: str = "") -> None:
        if self.text() != text:
            self.setText(text)
        self.set_level(level)
        self.setToolTip(tip)


class StationStatusBar(QStatusBar):
    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setSizeGripEnabled(False)
        self.state = Pill()
        self.scan = Pill()
        self.tick = Pill()
        self.nodes = Pill()
        self.records = Pill()
        self.server = Pill()
        self.forced = Pill()  # "F: n forced", always shown (netplc/forcing.py)
        self.consoles = Pill()  # the OPC UA sessions logged in (remote consoles...), while there are any
        for pill in (self.state, self.forced, self.scan, self.tick, self.nodes, self.records, self.server,
                     self.consoles):
            self.addPermanentWidget(pill)

    def show_status(self, s: RuntimeStatus) -> None:
        running = s.state == "running"
        self.state.show_value(self.tr("NetPlc: {0}").format(self.tr(s.state)), OK if running else BAD)
        self.forced.show_value(self.tr("F: {0} forced").format(s.forced), WARN if s.forced else IDLE,
                               self.tr("forces in effect: force > program > live (Station -> Program)"))
        late = s.scan_last_ms > s.tick_ms
        scan = self.tr("Scan {0:.2f} ms  max {1:.2f} ms").format(s.scan_last_ms, s.scan_max_ms)
        self.scan.show_value(scan,
                             WARN if late else OK,
                             self.tr("{0} scans, mean {1:.3f} ms, {2} overruns").format(
                                 s.scans, s.scan_mean_ms, s.overruns))
        self.tick.show_value(self.tr("Tick {0} ms").format(s.tick_ms), WARN if s.overruns else OK,
                             self.tr("NetSyncTime {0} ms; {1} scans took longer").format(
                                 s.tick_ms, s.overruns))
        down = [n for n in s.nodes if not n.up]
        links = "  ".join(f"{n.node}{UP if n.up else DOWN}" for n in s.nodes)
        self.nodes.show_value(self.tr("Nodes {0}/{1}").format(s.nodes_up, len(s.nodes)) + f"  {links}",
                              IDLE if not s.nodes else (BAD if down else OK),
                              "\n".join(f"node {n.node} {n.endpoint}: {'up' if n.up else 'DOWN'}"
                                        for n in s.nodes))
        archive_bad = s.records_lost > 0 or any(p.startswith("archive") for p in s.problems)
        self.records.show_value(self.tr("Archive {0} records").format(s.records_written),
                                BAD if archive_bad else (WARN if s.records_pending > 10_000 else OK),
                                self.tr("{0} waiting, {1} lost").format(s.records_pending, s.records_lost))
        if s.modbus_port:
            self.server.show_value(f"Modbus :{s.modbus_port}", OK,
                                   self.tr("NetPlc memory served over Modbus TCP"))
        elif s.modbus_serial:
            fault = next((p for p in s.problems if p.startswith("Modbus RTU")), "")
            self.server.show_value(f"Modbus RTU {s.modbus_serial}", BAD if fault else OK,
                                   fault or self.tr("NetPlc memory served over Modbus RTU"))
        else:
            self.server.show_value(self.tr("Modbus off"), IDLE)
        self.consoles.setVisible(bool(s.consoles))
        self.consoles.show_value(self.tr("Consoles {0}").format(len(s.consoles)), OK, "\n".join(s.consoles))


# the engine's state texts, for the translation sources (the status bar translates them as shown)
STATES = (QT_TRANSLATE_NOOP("StationStatusBar", "running"), QT_TRANSLATE_NOOP("StationStatusBar", "stopped"),
          QT_TRANSLATE_NOOP("StationStatusBar", "halted"), QT_TRANSLATE_NOOP("StationStatusBar", "idle"))


def station_problems(s: RuntimeStatus) -> list[str]:
    """What the health strip lists, in the console's language: forces in effect (a force left
    behind after commissioning is the costliest thing to miss), a stopped program, dead links;
    archive and server failures as the runtime words them."""
    problems: list[str] = []
    if s.forced:
        problems.append(QCoreApplication.translate("StationStatusBar", "{0} forces active").format(s.forced))
    if s.state != "running":
        state = QCoreApplication.translate("StationStatusBar", s.state)
        problems.append(QCoreApplication.translate("StationStatusBar", "NetPlc program {0}").format(state))
    if s.scans * s.tick_ms > STARTUP_GRACE_MS:
        no_link = QCoreApplication.translate("StationStatusBar", "no link to node {0} ({1})")
        problems += [no_link.format(n.node, n.endpoint) for n in s.nodes if not n.up]
    problems += list(s.problems)
    return problems
