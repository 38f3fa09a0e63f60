"""The workstation's status bar: NetPlc state, scan time, tick, node links, archive.

Each item is a small pill whose colour says at a glance whether it is well (green), needs
attention (amber) or is failing (red), with the figures beside it for whoever looks closer.
"""

from __future__ import annotations

from PySide6.QtWidgets import QLabel, QStatusBar, QWidget

from app.runtime import RuntimeStatus

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
        for pill in (self.state, self.forced, self.scan, self.tick, self.nodes, self.records, self.server):
            self.addPermanentWidget(pill)

    def show_status(self, s: RuntimeStatus) -> None:
        running = s.state == "running"
        self.state.show_value(f"NetPlc: {s.state}", OK if running else BAD)
        self.forced.show_value(f"F: {s.forced} forced", WARN if s.forced else IDLE,
                               "forces in effect: force > program > live (Station -> Program)")
        late = s.scan_last_ms > s.tick_ms
        self.scan.show_value(f"Scan {s.scan_last_ms:.2f} ms  max {s.scan_max_ms:.2f} ms",
                             WARN if late else OK,
                             f"{s.scans} scans, mean {s.scan_mean_ms:.3f} ms, {s.overruns} overruns")
        self.tick.show_value(f"Tick {s.tick_ms} ms", WARN if s.overruns else OK,
                             f"NetSyncTime {s.tick_ms} ms; {s.overruns} scans took longer")
        down = [n for n in s.nodes if not n.up]
        links = "  ".join(f"{n.node}{UP if n.up else DOWN}" for n in s.nodes)
        self.nodes.show_value(f"Nodes {s.nodes_up}/{len(s.nodes)}  {links}",
                              IDLE if not s.nodes else (BAD if down else OK),
                              "\n".join(f"node {n.node} {n.endpoint}: {'up' if n.up else 'DOWN'}"
                                        for n in s.nodes))
        archive_bad = s.records_lost > 0 or any(p.startswith("archive") for p in s.problems)
        self.records.show_value(f"Archive {s.records_written} records",
                                BAD if archive_bad else (WARN if s.records_pending > 10_000 else OK),
                                f"{s.records_pending} waiting, {s.records_lost} lost")
        if s.modbus_port:
            self.server.show_value(f"Modbus :{s.modbus_port}", OK, "NetPlc memory served over Modbus TCP")
        else:
            self.server.show_value("Modbus off", IDLE)


def station_problems(s: RuntimeStatus) -> list[str]:
    """What the health strip lists: a stopped program, dead links, archive and server failures."""
    problems: list[str] = []
    if s.state != "running":
        problems.append(f"NetPlc program {s.state}")
    if s.scans * s.tick_ms > STARTUP_GRACE_MS:
        problems += [f"no link to node {n.node} ({n.endpoint})" for n in s.nodes if not n.up]
    problems += list(s.problems)
    return problems
