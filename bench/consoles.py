"""Remote consoles on one headless station: latency, the station's CPU with 0, 1 and 8 consoles,
and a console's CPU beside the local workstation's on the same form.

The station is the demo run headless (`python main.py --no-gui`) in a process of its own, serving
OPC UA on a free loopback port; the consoles run in this process (offscreen Qt at 1366x768), each
a `ConsoleWindow` logged in as "operator" showing the demo's analog form, polling every 100 ms
(the demo's tick). The station's CPU is its process's (utime + stime from /proc) over each phase's
wall time, in % of one core. Latency is from the scan (its wall time, the memory variables' source
timestamp) to the paint of the console's form that shows it (the paint after the newest readings;
a scan that changed nothing on the form paints nothing), over every console and paint of the
8-console phase. The local workstation's cost on the same form
is measured as bench/workstation.py does: this process with a headless runtime alone, then with
the window shown on it; the window's share is the difference.

    QT_QPA_PLATFORM=offscreen python bench/consoles.py [--seconds 15]
"""

from __future__ import annotations

import argparse
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from PySide6.QtCore import QEvent, QObject
from PySide6.QtWidgets import QApplication

from app.gui.application import application
from app.gui.console.source import StationSource
from app.gui.console.window import ConsoleWindow
from app.gui.main_window import MainWindow
from app.gui.screenshots import copy_station
from app.publish.console import ConsoleClient
from app.scada.readings import Readings
from app.station.config import load_station
from app.station.runtime import Runtime

ROOT = Path(__file__).resolve().parents[1]
SIZE = (1366, 768)
FORM = 1  # the demo's analog form (02_analog.hmi), as the third tab
CONSOLES = 8
TICKS = os.sysconf("SC_CLK_TCK")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def pump(app: QApplication, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        app.processEvents()
        time.sleep(0.005)


def cpu_seconds(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS  # utime, stime


def measure(app: QApplication, station: int, seconds: float) -> tuple[float, float]:
    """% of one core of the station's process and of this one over `seconds` of the event loop."""
    s0, c0, w0 = cpu_seconds(station), time.process_time(), time.monotonic()
    pump(app, seconds)
    wall = time.monotonic() - w0
    return 100 * (cpu_seconds(station) - s0) / wall, 100 * (time.process_time() - c0) / wall


class Latency(QObject):
    """From a scan's wall time to the next paint of a console's form after its readings came."""

    def __init__(self, window: ConsoleWindow, samples: list[float]) -> None:
        super().__init__(window)
        self.samples = samples
        self.pending: float | None = None
        self.recording = False
        window.source.readings.connect(self._readings)
        area = window.tabs.widget(FORM)
        area.viewport().installEventFilter(self)

    def _readings(self, readings: Readings) -> None:
        self.pending = readings.snapshot.wall  # the paint shows the newest (no change: no paint)

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if event.type() == QEvent.Type.Paint and self.pending is not None:
            if self.recording:
                self.samples.append(time.time() - self.pending)
            self.pending = None
        return False


def console(app: QApplication, url: str, folder: Path) -> ConsoleWindow:
    client = ConsoleClient(url, folder=folder, period=0.1)
    client.discover().result(30)
    client.open("operator", "operator").result(30)
    window = ConsoleWindow(StationSource(client))
    window.resize(*SIZE)
    window.show()
    end = time.monotonic() + 30
    while len(window.views) <= FORM:
        if time.monotonic() > end:
            raise RuntimeError(f"{url}: the console shows no forms within 30 s")
        pump(app, 0.05)
    window.tabs.setCurrentIndex(FORM)
    return window


def start_station(folder: Path) -> tuple[subprocess.Popen[bytes], str]:
    port = free_port()
    url = f"opc.tcp://127.0.0.1:{port}/netplc/"
    toml = folder / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8") + f'\n[opcua]\nenabled = true\nendpoint = "{url}"\n',
                    encoding="utf-8")
    proc = subprocess.Popen([sys.executable, str(ROOT / "main.py"), "--no-gui", str(folder)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=ROOT)
    end = time.monotonic() + 60
    while True:
        try:
            socket.create_connection(("127.0.0.1", port), 0.2).close()
            return proc, url
        except OSError:
            if time.monotonic() > end or proc.poll() is not None:
                proc.kill()
                raise RuntimeError("the station did not serve OPC UA within 60 s") from None
            time.sleep(0.2)


def percentile(values: list[float], p: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(p / 100 * (len(ordered) - 1)))]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=15.0, help="length of each measured phase (default 15)")
    args = ap.parse_args(argv)
    app = application()
    with tempfile.TemporaryDirectory() as tmp:
        proc, url = start_station(copy_station(Path(tmp) / "station"))
        windows: list[ConsoleWindow] = []
        try:
            pump(app, 3.0)  # the station settles
            idle, _ = measure(app, proc.pid, args.seconds)
            windows.append(console(app, url, Path(tmp) / "config"))
            pump(app, 2.0)
            one, one_console = measure(app, proc.pid, args.seconds)
            samples: list[float] = []
            for _ in range(CONSOLES - 1):
                windows.append(console(app, url, Path(tmp) / "config"))
            latencies = [Latency(w, samples) for w in windows]
            pump(app, 2.0)
            for latency in latencies:
                latency.recording = True
            eight, eight_consoles = measure(app, proc.pid, args.seconds)
            for latency in latencies:
                latency.recording = False
        finally:
            for window in windows:
                window.close()
            proc.terminate()
            proc.wait(30)
        pump(app, 0.5)
        runtime = Runtime(load_station(copy_station(Path(tmp) / "local")))
        runtime.start()
        try:
            pump(app, 3.0)
            _, alone = measure(app, os.getpid(), args.seconds)
            window = MainWindow(runtime)
            window.resize(*SIZE)
            window.show()
            window.tabs.setCurrentIndex(FORM)
            pump(app, 2.0)
            _, with_window = measure(app, os.getpid(), args.seconds)
            window.close()
        finally:
            runtime.stop()
    local = with_window - alone
    print(f"station CPU, % of one core: {idle:.2f} with no console, {one:.2f} with 1 (+{one - idle:.2f}), "
          f"{eight:.2f} with {CONSOLES} (+{(eight - idle) / CONSOLES:.2f} per console)")
    print(f"latency scan -> console paint over {CONSOLES} consoles, {len(samples)} paints: "
          f"p50 {1000 * statistics.median(samples):.0f} ms, p99 {1000 * percentile(samples, 99):.0f} ms "
          f"(tick 100 ms, poll 100 ms)")
    print(f"console CPU on the analog form: {one_console:.2f} % of one core for 1 console, "
          f"{eight_consoles / CONSOLES:.2f} % each with {CONSOLES}; the local workstation's window on "
          f"the same form adds {local:.2f} % ({with_window:.2f} with, {alone:.2f} runtime alone): "
          f"{one_console / local if local > 0 else float('inf'):.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
