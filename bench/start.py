"""Start of a station with a full 8 K-word program, from process start to its first scan.

Each run is a fresh `python` process doing what `python main.py --no-gui STATION` does (import,
read station.toml, load messages and program, start the archive, Modbus server and scan thread)
and stopping at the first finished scan (once the compiled code runs the scans: a cold start scans
with the interpreter while a child process compiles, netplc/compile_behind.py, and the row says when
the compiled code took over). Runs alternate between a cold start (no compiled or parsed
program kept beside the archive) and a warm one (those of the previous start), interleaved with the
yardsticks: `python -c pass` (the interpreter alone) and a process that imports exactly the
modules the station's start loaded, in the order it loaded them, and does nothing else. That is
fair: it is the least any start of this station can cost, so start / imports says what the
station adds to its imports (issue 28: start <= 1.3x), and a module the configuration does
not use (Qt, pymodbus, the form code) would count against neither. Each row: median and worst.
Target (issue 16): first scan <= 0.5 s after the process starts.

    .venv/bin/python bench/start.py [--runs N]
"""

from __future__ import annotations

import argparse
import json
import random
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "bench")]

from scan import generate, pick_functions  # noqa: E402  (bench/scan.py: the same program)

TOML = """NetPlcProgram = "program.stl"
Messages = "messages.csv"
Archive = "archive/journal.sqlite"
[modbus_server]
port = 0
"""

# the child: timestamps (time.time(), comparable with the parent's) of each phase, as JSON
CHILD = """
import json, sys, time
t = {"main": time.time()}
sys.path.insert(0, sys.argv[2])
from app.station.config import load_station
from app.station.runtime import Runtime
t["imported"] = time.time()
station = load_station(sys.argv[1])
runtime = Runtime(station)
t["loaded"] = time.time()
runtime.start()
t["started"] = time.time()
while runtime.engine.stats.count < 1:
    time.sleep(0.0002)
t["first_scan"] = time.time()
runtime.engine.compiled_ready.wait(60)
t["compiled"] = time.time()
runtime.stop()
print(json.dumps(t))
print(json.dumps(list(sys.modules)))
"""

# the yardstick: the modules a start loaded, imported in the same order, nothing else
IMPORTS = """
import importlib, json, sys
sys.path.insert(0, sys.argv[2])
for name in json.loads(open(sys.argv[1], encoding="utf-8").read()):
    if name not in sys.modules:
        importlib.import_module(name)
"""


def make_station(folder: Path) -> int:
    text, _ = generate(random.Random(165), pick_functions())
    (folder / "program.stl").write_text(text, encoding="utf-8")
    (folder / "messages.csv").write_text("number,group,type,text\n1,1,0,Пуск\n", encoding="utf-8")
    (folder / "station.toml").write_text(TOML, encoding="utf-8")
    return len(text.splitlines())


def timed(args: list[str]) -> tuple[float, dict]:
    """Seconds from just before the process is created to its end, and what it printed."""
    t0 = time.time()
    r = subprocess.run([sys.executable, *args], capture_output=True, text=True, check=True, cwd=ROOT)
    end = time.time()
    lines = r.stdout.splitlines()
    phases = {k: v - t0 for k, v in json.loads(lines[0]).items()} if lines else {}
    if len(lines) > 1:
        phases["modules"] = lines[1]
    return end - t0, phases


def phases_in_process(station: Path) -> str:
    """Where a cold start's load and compile go, measured in this process (best of 3 each)."""
    from netplc import compiler
    from netplc.codecache import CodeCache
    from netplc.engine import Engine, FakeClock
    from netplc.parsecache import ParseCache, parse_file_cached
    from netplc.program import parse_file

    def best(fn) -> float:
        times = []
        for _ in range(3):
            t = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t)
        return min(times) * 1e3

    program = parse_file(station / "program.stl")
    engine = Engine(program, clock=FakeClock(), compiled=False)
    inline, _ = compiler.fon_code(engine)
    source = compiler.generate_source(program, inline)
    cache = station / "phases-cache"
    assert Engine(program, clock=FakeClock(), code_cache=cache).compiled_ready.wait(60)  # a child compiles it
    parsed = ParseCache(station / "phases-parsed")
    parse_file_cached(station / "program.stl", {}, parsed)
    figures = {
        "parse": best(lambda: parse_file(station / "program.stl")),
        "parse, from the cache": best(lambda: parse_file_cached(station / "program.stl", {}, parsed)),
        "generate Python": best(lambda: compiler.generate_source(program, inline)),
        "compile()": best(lambda: compile(source, "<bench>", "exec")),
        "engine, compiled": best(lambda: Engine(program, clock=FakeClock())),
        "engine, from the cache": best(lambda: Engine(program, clock=FakeClock(), code_cache=cache)),
    }
    assert CodeCache(cache).load(compiler.program_key(program, inline)) is not None
    return ", ".join(f"{k} {v:.0f} ms" for k, v in figures.items()) + f" ({len(source):,} chars of Python)"


def spread(values: list[float]) -> str:
    return f"median {statistics.median(values):.0f}, worst {max(values):.0f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        station = Path(tmp)
        lines = make_station(station)
        print(f"station: {lines}-line program of 8192 words (bench/scan.py, seed 165), archive, "
              f"Modbus server; {args.runs} runs of each, interleaved")
        caches = [station / "archive" / "compiled", station / "archive" / "parsed"]
        needed = station / "modules.json"  # what a start loaded, for the imports yardstick
        timed(["-c", CHILD, str(station), str(ROOT)])  # a first start: the cache and the module list
        needed.write_text(timed(["-c", CHILD, str(station), str(ROOT)])[1]["modules"], encoding="utf-8")
        names = ("python -c pass", "imports", "cold", "warm")
        rows: dict[str, list[float]] = {k: [] for k in names}
        parts: dict[str, list[dict]] = {"cold": [], "warm": []}
        for _ in range(args.runs):
            rows["python -c pass"].append(timed(["-c", "pass"])[0] * 1e3)
            rows["imports"].append(timed(["-c", IMPORTS, str(needed), str(ROOT)])[0] * 1e3)
            for kind in ("cold", "warm"):
                if kind == "cold":
                    for cache in caches:
                        shutil.rmtree(cache, ignore_errors=True)
                _, phases = timed(["-c", CHILD, str(station), str(ROOT)])
                rows[kind].append(phases["first_scan"] * 1e3)
                parts[kind].append(phases)
        count = len(json.loads(needed.read_text(encoding="utf-8")))
        print(f"  yardsticks: python -c pass {spread(rows['python -c pass'])} ms; importing the {count} "
              f"modules a start loads {spread(rows['imports'])} ms")
        for kind in ("cold", "warm"):
            p = {k: statistics.median(ph[k] for ph in parts[kind]) * 1e3
                 for k in parts[kind][0] if k != "modules"}
            ratios = [s / i for s, i in zip(rows[kind], rows["imports"], strict=True)]
            print(f"  {kind} start: first scan {spread(rows[kind])} ms after the process was created, "
                  f"{statistics.median(ratios):.2f}x the imports (worst run {max(ratios):.2f}x); medians: "
                  f"interpreter up {p['main']:.0f}, imports {p['imported'] - p['main']:.0f}, "
                  f"station + messages + program (parse) {p['loaded'] - p['imported']:.0f}, "
                  f"archive + engine (compile) + server "
                  f"{p['started'] - p['loaded']:.0f}, first scan {p['first_scan'] - p['started']:.0f} ms; "
                  f"scans on compiled code from {p['compiled']:.0f} ms")
        print(f"  in process: {phases_in_process(station)}")
        worst = {kind: max(s / i for s, i in zip(rows[kind], rows["imports"], strict=True))
                 for kind in ("cold", "warm")}
        fast = max(statistics.median(rows["cold"]), statistics.median(rows["warm"])) <= 500
        verdicts = "; ".join(f"{kind} {'met' if w <= 1.3 else 'NOT met'} (worst {w:.2f}x)"
                             for kind, w in worst.items())
        print(f"target start <= 1.3x the imports in every run: {verdicts}; first scan <= 500 ms (median, "
              f"cold and warm): {'met' if fast else 'NOT met'}")


if __name__ == "__main__":
    main()
