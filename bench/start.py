"""Start of a station with a full 8 K-word program, from process start to its first scan.

Each run is a fresh `python` process doing what `python main.py --no-gui STATION` does (import,
read station.toml, load messages and program, start the archive, Modbus server and scan thread)
and stopping at the first finished scan. Runs alternate between a cold start (no compiled-program
cache beside the archive) and a warm one (the cache of the previous start), and with the
yardsticks measured in the same run: `python -c pass` (the interpreter alone) and a process that
only imports the packages. Target (issue 16): first scan <= 0.5 s after the process starts.

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
runtime.stop()
print(json.dumps(t))
"""


def make_station(folder: Path) -> int:
    text, _ = generate(random.Random(165), pick_functions())
    (folder / "program.stl").write_text(text, encoding="utf-8")
    (folder / "messages.csv").write_text("number,group,type,text\n1,1,0,Пуск\n", encoding="utf-8")
    (folder / "station.toml").write_text(TOML, encoding="utf-8")
    return len(text.splitlines())


def timed(args: list[str]) -> tuple[float, dict[str, float]]:
    """Seconds from just before the process is created to its end, and what it printed."""
    t0 = time.time()
    r = subprocess.run([sys.executable, *args], capture_output=True, text=True, check=True, cwd=ROOT)
    end = time.time()
    phases = {k: v - t0 for k, v in json.loads(r.stdout).items()} if r.stdout.strip() else {}
    return end - t0, phases


def phases_in_process(station: Path) -> str:
    """Where a cold start's load and compile go, measured in this process (best of 3 each)."""
    from netplc import compiler
    from netplc.codecache import CodeCache
    from netplc.engine import Engine, FakeClock
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
    Engine(program, clock=FakeClock(), code_cache=cache)
    figures = {
        "parse": best(lambda: parse_file(station / "program.stl")),
        "generate Python": best(lambda: compiler.generate_source(program, inline)),
        "compile()": best(lambda: compile(source, "<bench>", "exec")),
        "engine, compiled": best(lambda: Engine(program, clock=FakeClock())),
        "engine, from the cache": best(lambda: Engine(program, clock=FakeClock(), code_cache=cache)),
    }
    assert CodeCache(cache).load(compiler.program_key(program, inline)) is not None
    return ", ".join(f"{k} {v:.0f} ms" for k, v in figures.items()) + f" ({len(source):,} chars of Python)"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        station = Path(tmp)
        lines = make_station(station)
        print(f"station: {lines}-line program of 8192 words (bench/scan.py, seed 165), archive, "
              f"Modbus server; {args.runs} runs of each, interleaved")
        cache = station / "archive" / "compiled"
        names = ("python -c pass", "import app.station.runtime", "cold", "warm")
        rows: dict[str, list[float]] = {k: [] for k in names}
        parts: dict[str, list[dict[str, float]]] = {"cold": [], "warm": []}
        for _ in range(args.runs):
            rows["python -c pass"].append(timed(["-c", "pass"])[0])
            imports = ["-c", "import app.station.config, app.station.runtime"]
            rows["import app.station.runtime"].append(timed(imports)[0])
            for kind in ("cold", "warm"):
                if kind == "cold":
                    shutil.rmtree(cache, ignore_errors=True)
                _, phases = timed(["-c", CHILD, str(station), str(ROOT)])
                rows[kind].append(phases["first_scan"])
                parts[kind].append(phases)
        med = {k: statistics.median(v) * 1e3 for k, v in rows.items()}
        for kind in ("cold", "warm"):
            p = {k: statistics.median(ph[k] for ph in parts[kind]) * 1e3 for k in parts[kind][0]}
            print(f"  {kind} start: first scan {med[kind]:.0f} ms after the process was created "
                  f"(min {min(rows[kind]) * 1e3:.0f}, max {max(rows[kind]) * 1e3:.0f}): interpreter up "
                  f"{p['main']:.0f}, imports {p['imported'] - p['main']:.0f}, station + messages + program "
                  f"{p['loaded'] - p['imported']:.0f}, archive + engine (compile) + server "
                  f"{p['started'] - p['loaded']:.0f}, first scan {p['first_scan'] - p['started']:.0f} ms")
        print(f"  yardsticks: python -c pass {med['python -c pass']:.0f} ms, importing the packages "
              f"{med['import app.station.runtime']:.0f} ms")
        bare, imports = med["python -c pass"], med["import app.station.runtime"]
        print(f"  warm start = {med['warm'] / bare:.1f}x python -c pass, "
              f"{med['warm'] / imports:.2f}x the imports alone; cold start "
              f"{med['cold'] / bare:.1f}x / {med['cold'] / imports:.2f}x")
        print(f"  in process: {phases_in_process(station)}")
        ok = med["cold"] <= 500 and med["warm"] <= 500
        print(f"target first scan <= 500 ms (cold and warm): {'met' if ok else 'NOT met'}")


if __name__ == "__main__":
    main()
