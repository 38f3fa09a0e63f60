"""Hot-standby pair figures (issue 26): the cost of mirroring, and takeovers over N kills.

1. The cost: station A runs alone for `--seconds`, then with B (a `main.py --no-gui` child, so
   A's process CPU is A's own) attached as its standby; A's mean scan time (the scan and its
   listeners, the mirror's capture among them) and A's process CPU per second, and their ratios.
2. Takeovers: A and B in this process on loopback with a simulated node; a writer thread writes
   an increasing word to whichever is primary, each write waiting for its answer. The primary is
   killed (no more scans, the link cut with no word) `--kills` times, the killed one restarted as
   the standby each time. Takeover time (kill to the standby's role primary) p50 and max, and
   acknowledged writes lost (the new primary's word below the last acknowledged value). With
   `--plant` both forward to one plant archive (a throwaway PostgreSQL cluster of tests/pgcluster.py):
   at the end, records of the two local archives missing from it, and alarm transitions in it
   twice in a row (the same transition of the same alarm: journaled by the old primary in a last
   scan its standby did not hold yet when it was killed, and again by the new primary).

    .venv/bin/python bench/failover.py [--seconds S] [--kills N] [--plant]
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.authority import Source, Who  # noqa: E402
from app.station.config import load_station  # noqa: E402
from app.station.runtime import Runtime  # noqa: E402
from netplc.address import IO_BITS  # noqa: E402
from netplc.program import parse  # noqa: E402
from netplc.simulator import Simulator  # noqa: E402
from tests.app.pair.conftest import PROGRAM, STATION, free_port  # noqa: E402

TICK_MS = 20
WHO = Who("", Source.MODBUS, "bench")
TAGS = """name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description,hh,h,l,ll,deadband,\
on_delay,off_delay,alarm_when,priority,latching,suppress_by,quality_alarm
GEN,03752,bit,,,,,,,Generator 0.4 s,,,,,,,,1,4,,,
"""


def folders(base: Path, node: int, ports: dict[str, int], plant: str = "") -> dict[str, Path]:
    out = {}
    # forwarding: the alarm of the 0.4 s generator's bit, journaled by the primary at every change
    top = f'Archive = "{plant}"\nTags = "tags.csv"\n' if plant else ""
    for letter, other in (("A", "B"), ("B", "A")):
        folder = base / letter
        folder.mkdir(parents=True)
        (folder / "station.toml").write_text(STATION.format(
            tick=TICK_MS, node=node, letter=letter, listen=ports[letter], partner=ports[other],
            arbiter="none", top=top), encoding="utf-8")
        (folder / "pair.stl").write_text(PROGRAM, encoding="utf-8")
        (folder / "tags.csv").write_text(TAGS, encoding="utf-8")
        out[letter] = folder
    return out


def scan_cost(rt: Runtime, seconds: float) -> tuple[float, float]:
    """Mean ms of the scan and its listeners, and process CPU seconds per second."""
    engine = rt.engine
    assert engine is not None
    spent: list[float] = []
    last = [time.perf_counter()]

    def first(_snapshot: object) -> None:  # the first listener: the scan ended
        last[0] = time.perf_counter()

    def final(_snapshot: object) -> None:  # the last: the listeners ended
        spent.append(time.perf_counter() - last[0])

    engine._listeners = (("bench first", first), *engine._listeners, ("bench final", final))
    stats0, cpu0, wall0 = engine.stats.count, time.process_time(), time.monotonic()
    scan0 = engine.stats.mean_ms * stats0
    time.sleep(seconds)
    n = engine.stats.count - stats0
    scan_ms = (engine.stats.mean_ms * engine.stats.count - scan0) / max(n, 1)
    cpu = (time.process_time() - cpu0) / (time.monotonic() - wall0)
    engine._listeners = tuple(e for e in engine._listeners if not e[0].startswith("bench"))
    return scan_ms + 1000 * statistics.fmean(spent), cpu


def cost(base: Path, node: Simulator, seconds: float) -> None:
    ports = {"A": free_port(), "B": free_port()}
    paths = folders(base / "cost", node.port, ports)
    a = Runtime(load_station(paths["A"]))
    a.start()
    try:
        alone = scan_cost(a, seconds)
        child = subprocess.Popen([sys.executable, "main.py", "--no-gui", str(paths["B"])], cwd=ROOT,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            deadline = time.monotonic() + 30
            while a.pair is not None and a.pair.status().link is False and time.monotonic() < deadline:
                time.sleep(0.05)
            time.sleep(1)
            paired = scan_cost(a, seconds)
        finally:
            child.terminate()
            child.wait(30)
    finally:
        a.stop()
    print(f"mirroring cost at NetSyncTime {TICK_MS} ms: scan+listeners {alone[0]:.3f} -> {paired[0]:.3f} ms "
          f"(x{paired[0] / alone[0]:.2f}), CPU {alone[1] * 100:.1f} % -> {paired[1] * 100:.1f} % "
          f"(x{paired[1] / max(alone[1], 1e-9):.2f})")


def kills(base: Path, node: Simulator, n: int, plant: str = "") -> None:
    ports = {"A": free_port(), "B": free_port()}
    paths = folders(base / "kills", node.port, ports, plant)
    rts = {letter: Runtime(load_station(paths[letter])) for letter in "AB"}
    rts["A"].start()
    rts["B"].start()
    acked: dict[int, int] = {}  # the last value each runtime acknowledged, by its id
    stop = threading.Event()

    def primary() -> Runtime | None:
        return next((rt for rt in rts.values() if rt.pair is not None and rt.pair.role == "primary"), None)

    def writer() -> None:
        value = 0
        while not stop.is_set():
            rt = primary()
            if rt is None or rt.commands is None:
                time.sleep(0.005)
                continue
            value = (value + 1) & 0xFFFF
            try:
                if rt.commands.write_word(WHO, 0o4000, value).result(1).ok:
                    acked[id(rt)] = value
            except TimeoutError:  # asked of a station killed before it applied it: not acknowledged
                continue

    thread = threading.Thread(target=writer, daemon=True)
    thread.start()
    took: list[float] = []
    lag: list[int] = []
    lost = 0
    try:
        for _ in range(n):
            time.sleep(0.3)
            dead = primary()
            assert dead is not None
            letter = dead.station.redundancy.letter  # type: ignore[union-attr]
            other = rts["B" if letter == "A" else "A"]
            assert dead.scan_thread is not None and dead.pair is not None
            dead.scan_thread.stop()
            dead.scan_thread = None
            pair, dead.pair = dead.pair, None
            killed = time.monotonic()
            pair.kill()
            while other.pair is None or other.pair.role != "primary":
                time.sleep(0.001)
            took.append(time.monotonic() - killed)
            dead.stop()  # its last commits answer the writes of its last scans
            last = acked.get(id(dead), 0)
            lag.append(other.pair.status().lag)
            image = other.pair.mirror.image  # the state the new primary led from
            if image[IO_BITS] | image[IO_BITS + 1] << 8 < last:
                lost += 1
            rts[letter] = Runtime(load_station(paths[letter]))
            rts[letter].start()
            back = rts[letter].pair
            while back is None or back.role != "standby" or not back.mirror.complete:
                time.sleep(0.005)  # the next kill once the pair is whole again
    finally:
        stop.set()
        thread.join(5)
        for rt in rts.values():
            rt.stop()
    failover = 3 * TICK_MS
    print(f"{n} kills at NetSyncTime {TICK_MS} ms (failover_after 3 = {failover} ms): takeover "
          f"p50 {statistics.median(took) * 1000:.0f} ms, max {max(took) * 1000:.0f} ms; "
          f"kills with an acknowledged write lost: {lost}; the standby's lag at the takeover: "
          f"max {max(lag)} scans")
    if plant:
        missing, doubled, total = plant_check(plant, paths)
        print(f"plant archive: {total} records of the pair, {missing} of the local archives missing, "
              f"{doubled} alarm transitions twice in a row")


def plant_check(url: str, paths: dict[str, Path]) -> tuple[int, int, int]:
    """Records of both local archives missing from the plant archive, records in it twice."""
    import sqlite3

    import psycopg

    from registrar.plant.schema import PAIR_ID_BASE
    from registrar.schema import DAY_GLOB

    ours: set[int] = set()
    for letter, folder in paths.items():
        con = sqlite3.connect(load_station(folder).Archive)
        for (name,) in con.execute("SELECT name FROM sqlite_master WHERE type = 'table' AND name GLOB ?",
                                   (DAY_GLOB,)):
            ours |= {i + PAIR_ID_BASE[letter] for (i,) in con.execute(f'SELECT id FROM "{name}"')}
        con.close()
    with psycopg.connect(url) as pg:
        ids = {i for (i,) in pg.execute("SELECT id FROM records WHERE station = 'pair'")}
        alarms = pg.execute("SELECT source, number, type FROM records WHERE station = 'pair' "
                            "AND kind = 'alarm' ORDER BY ts, id").fetchall()
    doubled = sum(1 for before, row in itertools.pairwise(alarms) if before == row)
    return len(ours - ids), doubled, len(ids)

def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=5.0)
    p.add_argument("--kills", type=int, default=20)
    p.add_argument("--plant", action="store_true", help="forward to a throwaway PostgreSQL cluster")
    args = p.parse_args()
    node = Simulator(parse("JMP 0\n", "node.stl"), tick=TICK_MS / 1000)
    node.start()
    cluster = None
    try:
        url = ""
        if args.plant:
            from tests.pgcluster import PgCluster

            cluster = PgCluster()
            cluster.start()
            url = cluster.create_database("failover")
        with tempfile.TemporaryDirectory() as d:
            if args.seconds:
                cost(Path(d), node, args.seconds)
            kills(Path(d), node, args.kills, url)
    finally:
        node.stop()
        if cluster is not None:
            cluster.remove()


if __name__ == "__main__":
    main()
