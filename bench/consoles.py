"""Remote consoles on one headless station, every console a process of its own as at a plant:
latency, the station's CPU with 0, 1 and 8 consoles, each console's CPU beside the local
workstation's on the same form, and one console on a 3,000-element form beside the workstation.

The station is the demo run headless (`python main.py --no-gui`) in a process of its own, serving
OPC UA on a free loopback port. Each console is `python bench/consoles.py --console URL` (offscreen
Qt at 1366x768): a `ConsoleWindow` logged in as "operator" showing the demo's analog form, which
watches what the form reads (a handful of words, pushed by the station at each change). Every
process's CPU is its own rusage (utime + stime, every thread) over the phase's wall time, in % of
one core: the station's from /proc, a console's by itself. Latency is from the scan (its wall
time, NetPlc.Tick's source timestamp) to the paint of the console's form that shows it (the
paint after the newest readings; a scan that changed nothing on the form paints nothing), over
every console and paint of a phase. The first console's cost is measured in rounds that alternate
the station alone and the station with one console (a new console process each round, its start
and login outside the phase), each round's difference its cost: a load that drifts over the run
falls on both halves of a round alike. Each phase with consoles starts SETTLE_S after they
logged in: what a console reads once at its start (the journal's first page, its trends' hour of
history) is not what it costs the station from then on. The 8 consoles' phase is compared
with the median of the phases alone. The local workstation's cost on the same form is measured
as bench/workstation.py does: this process with a headless runtime alone, then with the window
shown on it, in as many rounds as the consoles' (a new window each round); the window's share is
the median of the rounds' differences.

The 3,000-element form is bench/hmi.py's (two dials, two lamps, a readout and a bar per six
elements, its words moved to banks 1-3 and its lamps to data bits of bank 4), added to a copy of
the demo whose program shifts banks 1-4 by a word at every scan behind a counter, so every word
changes at every tick by 256 raw. One console shows it; then the local workstation shows it; each
is quoted with its scan -> paint latency and the share of scans its form painted.

    QT_QPA_PLATFORM=offscreen python bench/consoles.py [--seconds 10] [--rounds 4] [--consoles 8]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import select
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # run as a script: the repository's packages, and bench/hmi.py

from PySide6.QtCore import QEvent, QObject  # noqa: E402
from PySide6.QtWidgets import QApplication, QScrollArea  # noqa: E402

from app.gui.application import application  # noqa: E402
from app.gui.screenshots import copy_station  # noqa: E402
from app.scada.readings import Readings  # noqa: E402
from bench.hmi import generate  # noqa: E402

SIZE = (1366, 768)
ANALOG = 1  # the demo's analog form (02_analog.hmi), the second tab
BIG = 3  # the generated form, after the demo's three
BIG_ELEMENTS = 3000
CONSOLES = 8
START_S = 180.0  # a station's start, on a machine loaded by other work
SETTLE_S = 3.0  # after a console's login: its first pages of the journal and the trends' history read
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


def own_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def percentile(values: list[float], p: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(p / 100 * (len(ordered) - 1)))] if ordered else float("nan")


class Latency(QObject):
    """From a scan's wall time to the next paint of a form after readings of it came; the scans
    painted."""

    def __init__(self, area: QScrollArea, readings: object) -> None:
        super().__init__(area)
        self.samples: list[float] = []
        self.painted: set[int] = set()
        self.pending: tuple[float, int] | None = None
        self.recording = False
        readings.connect(self._readings)  # type: ignore[attr-defined]
        area.viewport().installEventFilter(self)

    def _readings(self, readings: Readings) -> None:
        self.pending = (readings.snapshot.wall, readings.snapshot.scan)  # the paint shows the newest

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if event.type() == QEvent.Type.Paint and self.pending is not None:
            if self.recording:
                self.samples.append(time.time() - self.pending[0])
                self.painted.add(self.pending[1])
            self.pending = None
        return False


# --- a console: a process of its own --------------------------------------------------------------

def console_process(url: str, folder: Path, form: int) -> int:
    """Log in, show `form`, say "ready"; at each "go" on stdin measure `seconds` (the line's number)
    and print what was measured as a JSON line; end at "quit"."""
    from app.gui.console.source import StationSource
    from app.gui.console.window import ConsoleWindow
    from app.publish.client import LoginError
    from app.publish.console import ConsoleClient

    app = application()
    client = ConsoleClient(url, folder=folder, period=0.1)
    client.discover().result(60)
    for attempt in range(3):  # a loaded machine: asyncua's health probe may give up on a login
        try:
            client.open("operator", "operator").result(60)
            break
        except LoginError as e:
            print(f"login {attempt + 1} failed: {e}", file=sys.stderr)
            time.sleep(2.0)
    else:
        raise RuntimeError(f"{url}: no login in 3 attempts")
    window = ConsoleWindow(StationSource(client))
    window.resize(*SIZE)
    window.show()
    end = time.monotonic() + 120
    while len(window.views) <= form:
        if time.monotonic() > end:
            raise RuntimeError(f"{url}: the console shows no form {form} within 120 s")
        pump(app, 0.05)
    window.tabs.setCurrentIndex(form)
    probe = Latency(window.tabs.widget(form), window.source.readings)
    pump(app, 2.0)
    print("ready", flush=True)
    while True:
        line = ""
        while not line:
            app.processEvents()
            if select.select([sys.stdin], [], [], 0.005)[0]:
                line = sys.stdin.readline().strip() or "quit"
        if line == "quit":
            break
        seconds = float(line.split()[1])
        probe.samples, probe.painted = [], set()
        scan0 = client.memory.tick
        c0, w0 = own_cpu(), time.monotonic()
        probe.recording = True
        pump(app, seconds)
        probe.recording = False
        wall = time.monotonic() - w0
        print(json.dumps({"cpu": 100 * (own_cpu() - c0) / wall, "latency": probe.samples,
                          "painted": len(probe.painted), "scans": client.memory.tick - scan0,
                          "watched": client.memory.watched}), flush=True)
    window.close()
    return 0


@dataclass
class Measured:
    """What a console process measured over a phase."""

    cpu: float  # % of one core
    latency: list[float]  # s, scan -> paint
    painted: int  # scans painted
    scans: int  # scans over the phase
    watched: int  # parts of the memory watched


class Console:
    """A console process, driven through its stdin and stdout."""

    def __init__(self, url: str, folder: Path, form: int) -> None:
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        self.proc = subprocess.Popen([sys.executable, __file__, "--console", url, "--folder", str(folder),
                                      "--form", str(form)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True, env=env, cwd=ROOT)

    def ready(self) -> None:
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if line.strip() != "ready":
            raise RuntimeError(f"a console did not start: {line!r}")

    def go(self, seconds: float) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(f"go {seconds}\n")
        self.proc.stdin.flush()

    def result(self) -> Measured:
        assert self.proc.stdout is not None
        return Measured(**json.loads(self.proc.stdout.readline()))

    def stop(self) -> None:
        if self.proc.poll() is None:
            try:
                assert self.proc.stdin is not None
                self.proc.stdin.write("quit\n")
                self.proc.stdin.flush()
                self.proc.wait(30)
            except (OSError, subprocess.TimeoutExpired):
                self.proc.kill()
                self.proc.wait(10)


# --- the stations ---------------------------------------------------------------------------------

def big_station(folder: Path) -> Path:
    """The demo with the 3,000-element form and a program that moves every word of it each scan."""
    copy_station(folder)
    path = generate(folder / "forms", BIG_ELEMENTS, plots=False)
    doc = json.loads(path.read_text())
    for k, element in enumerate(doc["elements"]):
        if element["type"] == "AnalogBase":  # banks 0-2 -> 1-3, clear of the demo's own
            element["InAddr"] = f"0{int(element['InAddr'], 8) + 0o10000:o}"
        else:  # a lamp: a data bit of bank 4 (byte 044000 + k // 8)
            element["InAddr"] = f"0{(0o44000 + k // 8) * 8 + k % 8:o}"
    path.unlink()
    (folder / "forms" / "04_big.hmi").write_text(json.dumps(doc))
    lines, coil = [], 0o1000
    for bank in (1, 2, 3, 4):
        base = bank * 0o10000 + 0o4000
        hi = base + 2045
        while hi >= base:  # bytes base..base+2045 up by two, the top block first (MOVBLK: 256 at most)
            lo = max(base, hi - 253)
            lines += ["TNA ON", f"FON C:$0{coil:o} N:MOVBLK S:$0{lo:o} D:$0{hi:o} R:$0{lo + 2:o}"]
            coil, hi = coil + 4, lo - 1
        lines += ["TNA ON", f"FON C:$0{coil:o} N:INCW S:$0{base + 2046:o} D:$0{base + 1:o}"]  # +256 a scan
        coil += 4
    program = folder / "netplc.stl"
    program.write_text("\n".join(lines) + "\n" + program.read_text(encoding="utf-8"), encoding="utf-8")
    return folder


def start_station(folder: Path) -> tuple[subprocess.Popen[bytes], str]:
    port = free_port()
    url = f"opc.tcp://127.0.0.1:{port}/netplc/"
    toml = folder / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8") + f'\n[opcua]\nenabled = true\nendpoint = "{url}"\n',
                    encoding="utf-8")
    proc = subprocess.Popen([sys.executable, str(ROOT / "main.py"), "--no-gui", str(folder)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=ROOT)
    end = time.monotonic() + START_S
    while True:
        try:
            socket.create_connection(("127.0.0.1", port), 0.2).close()
            return proc, url
        except OSError:
            if time.monotonic() > end or proc.poll() is not None:
                proc.kill()
                raise RuntimeError(f"the station did not serve OPC UA within {START_S:g} s") from None
            time.sleep(0.2)


def station_cpu(pid: int, seconds: float, consoles: list[Console]) -> tuple[float, list[Measured]]:
    """% of one core of the station over `seconds` while `consoles` measure themselves."""
    for c in consoles:
        c.go(seconds)
    s0, w0 = cpu_seconds(pid), time.monotonic()
    time.sleep(seconds)
    station = 100 * (cpu_seconds(pid) - s0) / (time.monotonic() - w0)
    return station, [c.result() for c in consoles]


def local(app: QApplication, folder: Path, form: int, seconds: float, rounds: int = 1
          ) -> tuple[list[float], list[float], Latency]:
    """The local workstation on `form`: this process's CPU with its runtime alone and with the
    window shown on it (% of one core), in `rounds` that alternate the two (a new window each
    round, made and shown before its phase), and the latency of its form in the last round."""
    from app.gui.main_window import MainWindow
    from app.station.config import load_station
    from app.station.runtime import Runtime

    runtime = Runtime(load_station(folder))
    runtime.start()
    alone, shown = [], []
    try:
        pump(app, 3.0)
        for _ in range(rounds):
            c0, w0 = own_cpu(), time.monotonic()
            pump(app, seconds)
            alone.append(100 * (own_cpu() - c0) / (time.monotonic() - w0))
            window = MainWindow(runtime)
            window.resize(*SIZE)
            window.show()
            window.tabs.setCurrentIndex(form)
            probe = Latency(window.tabs.widget(form), window.bridge.readings)
            pump(app, 2.0)
            c0, w0 = own_cpu(), time.monotonic()
            probe.recording = True
            pump(app, seconds)
            probe.recording = False
            shown.append(100 * (own_cpu() - c0) / (time.monotonic() - w0))
            window.close()
            pump(app, 1.0)
    finally:
        runtime.stop()
    return alone, shown, probe


def ms(values: list[float]) -> str:
    if not values:
        return "no paint"
    return f"p50 {1000 * statistics.median(values):.0f} ms, p99 {1000 * percentile(values, 99):.0f} ms"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=10.0, help="length of each measured phase (default 10)")
    ap.add_argument("--rounds", type=int, default=4, help="rounds of no console and one console (default 4)")
    ap.add_argument("--consoles", type=int, default=CONSOLES, help=f"consoles of the last phase ({CONSOLES})")
    ap.add_argument("--console", help=argparse.SUPPRESS)  # a console process of the bench
    ap.add_argument("--folder", help=argparse.SUPPRESS)
    ap.add_argument("--form", type=int, default=ANALOG, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.console:
        return console_process(args.console, Path(args.folder), args.form)
    app = application()
    seconds = args.seconds
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        proc, url = start_station(copy_station(folder / "station"))
        consoles: list[Console] = []
        try:
            time.sleep(3.0)  # the station settles
            idles, ones, firsts = [], [], []
            for _ in range(args.rounds):
                idles.append(station_cpu(proc.pid, seconds, [])[0])
                consoles.append(Console(url, folder / "config", ANALOG))
                consoles[0].ready()
                time.sleep(SETTLE_S)
                one, (first,) = station_cpu(proc.pid, seconds, consoles)
                ones.append(one)
                firsts.append(first)
                consoles.pop().stop()
                time.sleep(1.0)  # the station ends the session
            for _ in range(args.consoles):
                consoles.append(Console(url, folder / "config", ANALOG))
            for c in consoles:
                c.ready()
            time.sleep(SETTLE_S)
            many, results = station_cpu(proc.pid, seconds, consoles)
        finally:
            for c in consoles:
                c.stop()
            proc.terminate()
            proc.wait(30)
        alones, with_windows, _ = local(app, copy_station(folder / "local"), ANALOG, seconds, args.rounds)
        big = big_station(folder / "big")
        proc, url = start_station(big)
        try:
            time.sleep(3.0)
            big_console = Console(url, folder / "config-big", BIG)
            big_console.ready()
            time.sleep(SETTLE_S)
            _, (big_result,) = station_cpu(proc.pid, seconds, [big_console])
        finally:
            big_console.stop()
            proc.terminate()
            proc.wait(30)
        toml = folder / "big" / "station.toml"  # the local workstation's own, without OPC UA
        toml.write_text(toml.read_text(encoding="utf-8").split("\n[opcua]")[0], encoding="utf-8")
        _, (big_local_cpu,), big_local = local(app, big, BIG, seconds)
    load = os.getloadavg()
    shares = [shown - alone for alone, shown in zip(alones, with_windows, strict=True)]
    share, alone, with_window = (statistics.median(v) for v in (shares, alones, with_windows))
    latencies = [x for r in results for x in r.latency]
    cpus = [r.cpu for r in results]
    idle = statistics.median(idles)
    costs = [one - alone for one, alone in zip(ones, idles, strict=True)]
    first = firsts[-1]
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} (1, 5, 15 min); phases of {seconds:g} s")
    print(f"station CPU, % of one core: {idle:.2f} with no console (median of {len(idles)}); "
          f"the first console +{statistics.median(costs):.2f} median, +{max(costs):.2f} worst "
          f"of {len(costs)} rounds "
          f"({', '.join(f'{alone:.2f} -> {one:.2f}' for alone, one in zip(idles, ones, strict=True))}); "
          f"{many:.2f} with {len(results)} (+{(many - idle) / len(results):.2f} per console)")
    print(f"latency scan -> console paint: 1 console {ms([x for f in firsts for x in f.latency])}; "
          f"{len(results)} consoles, {len(latencies)} paints: {ms(latencies)} (tick 100 ms)")
    worst = max(*cpus, *(f.cpu for f in firsts))
    print(f"console CPU on the analog form ({first.watched} parts of the memory watched): "
          f"{statistics.median(f.cpu for f in firsts):.2f} % "
          f"of one core alone; with {len(results)}: median {statistics.median(cpus):.2f}, worst "
          f"{max(cpus):.2f}; the local workstation's window on the same form adds {share:.2f} % "
          f"({with_window:.2f} with, {alone:.2f} runtime alone, medians of "
          f"{', '.join(f'+{v:.2f}' for v in shares)}): worst "
          f"{worst / share if share > 0 else float('inf'):.2f}x")
    print(f"{BIG_ELEMENTS}-element form, every word changing each tick: 1 console {ms(big_result.latency)}, "
          f"{big_result.painted} of {max(1, big_result.scans)} scans painted, {big_result.cpu:.1f} % of one "
          f"core ({big_result.watched} parts watched); the local workstation {ms(big_local.samples)}, "
          f"{len(big_local.painted)} scans painted in {seconds:g} s, {big_local_cpu:.1f} % of one core "
          "with its runtime")
    return 0


if __name__ == "__main__":
    sys.exit(main())
