"""Hot-standby pair figures (issue 26): the cost of mirroring, and takeovers over N kills.

1. The cost: station A runs alone for `--seconds`, then with B (a `main.py --no-gui` child, so
   A's process CPU is A's own) attached as its standby; A's mean scan time (the scan and its
   listeners, the mirror's capture among them) and A's process CPU per second, and their ratios.
2. Takeovers: A and B as processes of their own (`--serve`: the station loaded from its folder,
   made from tests/app/pair's template, and run as `main.py --no-gui` runs it, its Modbus and
   OPC UA ports put after loading since two stations on one host cannot share them) polling a
   simulated node. Two real clients write: a Modbus TCP client (netplc's LeanTcpClient) to
   register 1024 (word 04000) and an asyncua client logged in as an operator to the tag OPW
   (word 04002), each the values 1, 2, 3... once each, to whichever station accepts (exception 6
   / Bad_InvalidState: the standby), keeping the values acknowledged. The primary's process is
   SIGKILLed `--kills` times, restarted as the standby each time, the next kill once the pair is
   whole again. Takeover time: the kill to each client's first write acknowledged by the new
   primary, and to the new primary's journal record of its takeover. Every applied write is a
   record of the station's journal (value and word): lost = acknowledged and journaled by
   neither station, or the new primary's word, read before the first write to it, below the last
   value acknowledged; applied twice = one value journaled twice. The standby's lag (its
   HSB_LAG byte, read over Modbus) just before each kill. With
   `--plant` both forward to one plant archive (a throwaway PostgreSQL cluster of tests/pgcluster.py,
   on 127.0.0.1): at the end (the station killed last back as the standby first, so that it
   forwards what it committed before its kill), records of the two local archives missing from
   it (a record both hold, one a new primary archived for its partner, is one: its pid), records
   in it twice, alarm transitions in it twice in a row (the same transition of the same alarm:
   one record of an event made by both stations, or one missing between two), and writes applied
   that neither station journaled (a break in a word's chain of "old -> new"). Takeovers of a
   live primary (its standby heard nothing for failover_after: the primary journals TAKEN and
   follows) and flip-backs (two primaries meeting, one giving way) are counted from the journals.

    .venv/bin/python bench/failover.py [--seconds S] [--kills N] [--plant]
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import itertools
import logging
import os
import re
import signal
import sqlite3
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.authority.users import Users  # noqa: E402
from app.station.config import load_station  # noqa: E402
from app.station.pair import HSB_NUM_PLC  # noqa: E402
from app.station.runtime import Runtime  # noqa: E402
from netplc.modbus import BUSY  # noqa: E402
from netplc.modbus.client import LeanTcpClient  # noqa: E402
from netplc.modbus.endpoint import Endpoint  # noqa: E402
from netplc.modbus.pdu import DeviceError, LinkError  # noqa: E402
from netplc.program import parse  # noqa: E402
from netplc.simulator import Simulator  # noqa: E402
from registrar.schema import DAY_GLOB  # noqa: E402
from tests.app.pair.conftest import PROGRAM, STATION, free_port  # noqa: E402

TICK_MS = 20
NAME = "pair"  # the station's name (tests/app/pair's template): its OPC UA namespace
TAGS = """name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description,hh,h,l,ll,deadband,\
on_delay,off_delay,alarm_when,priority,latching,suppress_by,quality_alarm
GEN,03752,bit,,,,,,,Generator 0.4 s,,,,,,,,1,4,,,
OPW,04002,word,,0,65535,0,65535,0,The OPC UA writer's word,,,,,,,,,,,,
"""


def folders(base: Path, node: int, ports: dict[str, int], plant: str = "") -> dict[str, Path]:
    out = {}
    # forwarding: the alarm of the 0.4 s generator's bit, journaled by the primary at every change
    # and the OPC UA writer's tag
    top = (f'Archive = "{plant}"\n' if plant else "") + 'Tags = "tags.csv"\n'
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


MODBUS_WORD, OPCUA_WORD = 0o4000, 0o4002  # each writer's own word (register 1024, the tag OPW)
HSB_LAG_REGISTER = 0o77716 // 2  # the standby's lag in scans, the low byte (little-endian word)


def serve(folder: Path, modbus_port: int, opcua_url: str) -> None:
    """A station of the pair as a process of its own, until SIGTERM (or SIGKILL). The station's
    Modbus and OPC UA ports are put after loading (as tests/app/pair does): two stations on one
    host cannot listen on the same ports, and station.toml's ports count in the hash the pair
    compares (on two hosts both folders would be the same file)."""
    # the pair's own words in the bench's output: a link that does not come up says why
    logging.basicConfig(level=logging.WARNING, format=f"{folder.name} %(asctime)s %(name)s: %(message)s")
    logging.getLogger("app.station.pair").setLevel(logging.INFO)
    station = load_station(folder)
    station = replace(station, modbus_server=replace(station.modbus_server, port=modbus_port),
                      opcua=replace(station.opcua, enabled=True, endpoint=opcua_url, writable=("OPW",)))
    runtime = Runtime(station)
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda _signum, _frame: done.set())
    runtime.start()
    try:
        done.wait()
    finally:
        runtime.stop()


@dataclass
class Writer:
    """A client writing 1, 2, 3... to its own word of whichever station answers writes; each
    value is tried once (an unanswered one is not sent again: a retry would be the client's
    double). `acked`: (value, station index, monotonic time of the answer). `behind`: takeovers
    where the new primary's word, read before the first write to it, was below the last value
    acknowledged (an acknowledged write lost with the old primary)."""

    name: str
    acked: list[tuple[int, int, float]] = field(default_factory=list)
    behind: int = 0
    errors: int = 0

    def last(self) -> int:
        return self.acked[-1][0] if self.acked else 0


async def modbus_writer(w: Writer, ports: list[int], stop: threading.Event) -> None:
    clients = [LeanTcpClient(Endpoint("tcp", "127.0.0.1", p), timeout=1.0) for p in ports]
    at, value, checked = 0, 0, -1
    register = MODBUS_WORD // 2
    while not stop.is_set():
        client = clients[at]
        try:
            if not client.connected:
                await client.connect()
            if checked != at:  # the first write to this station: has it the last acknowledged value?
                (word,) = await client.read(1, "holding", register, 1)
            value += 1
            await client.write(1, "holding", register, [value])
        except DeviceError as e:  # 6: the standby (or busy): the other answers writes
            if e.code != BUSY:
                raise
            at = 1 - at
            await asyncio.sleep(0.002)
            continue
        except LinkError:  # killed (or not up yet): the other one
            client.close()
            at = 1 - at
            await asyncio.sleep(0.002)
            continue
        if checked != at:
            w.behind += word < w.last()
            checked = at
        w.acked.append((value, at, time.monotonic()))
    for client in clients:
        client.close()


async def opcua_writer(w: Writer, urls: list[str], stop: threading.Event) -> None:
    """Logged in as an operator to both stations (a client of a Hot pair keeps a session to
    each, Part 4 6.6.2), writing to the one that accepts; Bad_InvalidState: the standby."""
    from asyncua import Client, ua

    errors = (OSError, TimeoutError, ConnectionError, ua.UaError)
    clients: list[Client | None] = [None, None]

    async def drop(i: int) -> None:
        client, clients[i] = clients[i], None
        if client is not None:
            with contextlib.suppress(*errors):
                await asyncio.wait_for(client.disconnect(), 1)

    async def session(i: int) -> Client:
        client = clients[i]
        if client is None:
            client = Client(urls[i], timeout=2)
            client.set_user("op1")
            client.set_password("op1")
            await client.connect()
            clients[i] = client
        return client

    at, value, checked = 0, 0, -1
    while not stop.is_set():
        if clients[1 - at] is None:  # the partner's session, ready for a takeover
            try:
                await session(1 - at)
            except errors:
                await drop(1 - at)
        try:
            client = await session(at)
            ns = await client.get_namespace_index(f"urn:netplc:station:{NAME}")
            node = client.get_node(ua.NodeId("Tags.OPW", ns))
            word = await node.read_value()
            kind = (await node.read_data_value()).Value.VariantType
            until = time.monotonic() + 1  # then back to see to the partner's session
            while not stop.is_set() and time.monotonic() < until:
                value += 1
                await node.write_value(ua.DataValue(ua.Variant(value, kind)))
                if checked != at:
                    w.behind += word < w.last()
                    checked = at
                w.acked.append((value, at, time.monotonic()))
        except ua.uaerrors.BadInvalidState:  # the standby
            at = 1 - at
            await asyncio.sleep(0.002)
        except errors:  # killed, or not up yet
            w.errors += 1
            await drop(at)
            at = 1 - at
            await asyncio.sleep(0.002)
    for i in (0, 1):
        await drop(i)


def hsb(port: int) -> tuple[int, bool, int] | None:
    """The station's HSBStatus (4 standby, 5 primary), whether its pair link is up, and its lag
    in scans, read over Modbus (registers 16356-16359: the words 077710-077716); None: no answer."""
    async def read() -> list[int]:
        client = LeanTcpClient(Endpoint("tcp", "127.0.0.1", port), timeout=1.0)
        await client.connect()
        try:
            return await client.read(1, "holding", HSB_NUM_PLC // 2, 4)
        finally:
            client.close()

    try:
        words = asyncio.run(read())
    except (LinkError, DeviceError):
        return None
    return words[0] >> 8, not words[1] & 1 << 9, words[3] & 0xFF


def wait_until(condition: Callable[[], object], timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise SystemExit(f"not within {timeout} s: {what}")
        time.sleep(0.01)


def applied(folders: dict[str, Path], since_ms: int) -> dict[int, Counter[int]]:
    """The writes each word's journal says were applied, from the stations' local archives: by
    word, how many times each value was written (a write applied twice is counted twice; a record
    both stations hold, one a new primary archived for its partner, has one pid in both: once)."""
    out: dict[int, Counter[int]] = {MODBUS_WORD: Counter(), OPCUA_WORD: Counter()}
    seen: set[object] = set()
    for letter, folder in folders.items():
        con = sqlite3.connect(load_station(folder).Archive)
        try:
            for (name,) in con.execute("SELECT name FROM sqlite_master WHERE type = 'table' AND name GLOB ?",
                                       (DAY_GLOB,)):
                for number, value, key, pid in con.execute(
                        f"SELECT number, value, id, pid FROM \"{name}\" WHERE kind = 'operator' AND ts >= ? "
                        "AND text LIKE 'write %' AND number IN (?, ?)", (since_ms, MODBUS_WORD, OPCUA_WORD)):
                    identity = pid if pid is not None else (letter, name, key)
                    if identity not in seen:
                        seen.add(identity)
                        out[number][int(value)] += 1
        finally:
            con.close()
    return out


def journaled(folder: Path, like: str) -> list[int]:
    """ts (ms) of the station's journal records whose text is LIKE `like`."""
    con = sqlite3.connect(load_station(folder).Archive)
    try:
        return [ts for (name,) in con.execute(
                    "SELECT name FROM sqlite_master WHERE type = 'table' AND name GLOB ?", (DAY_GLOB,))
                for (ts,) in con.execute(f"SELECT ts FROM \"{name}\" WHERE text LIKE ?", (like,))]
    finally:
        con.close()


def takeovers(folder: Path) -> list[int]:
    """ts (ms) of the station's journal records of its takeovers (standby -> primary)."""
    return journaled(folder, "%standby -> primary%")


def kills(base: Path, node: Simulator, n: int, plant: str = "") -> None:
    ports = {"A": free_port(), "B": free_port()}
    paths = folders(base / "kills", node.port, ports, plant)
    modbus = [free_port(), free_port()]
    urls = [f"opc.tcp://127.0.0.1:{free_port()}/netplc/" for _ in "AB"]
    for folder in paths.values():
        Users(folder).add("op1", "operator", "op1")
    procs: dict[int, subprocess.Popen[bytes]] = {}

    def start(i: int) -> None:
        procs[i] = subprocess.Popen(
            [sys.executable, __file__, "--serve", str(paths["AB"[i]]), "--modbus-port", str(modbus[i]),
             "--opcua", urls[i]], cwd=ROOT, stdout=subprocess.DEVNULL)

    def role(i: int) -> int | None:
        status = hsb(modbus[i])
        return None if status is None else status[0]

    since = int(time.time() * 1000)
    writers = [Writer("Modbus"), Writer("OPC UA")]
    stop = threading.Event()
    threads = [threading.Thread(target=asyncio.run, args=(modbus_writer(writers[0], modbus, stop),)),
               threading.Thread(target=asyncio.run, args=(opcua_writer(writers[1], urls, stop),))]
    took: dict[str, list[float]] = {"Modbus": [], "OPC UA": [], "journal": []}
    lag: list[int] = []
    killings: list[tuple[float, str]] = []  # the wall time of each kill, the letter taking over
    stopped = ""  # why the kills ended early (a station too slow to start on an overloaded machine)
    dead: int | None = None  # a station killed and not restarted yet
    restarted = 1  # the station started last: B, or the one killed last
    try:  # the stations are stopped whatever happens (a first start too slow included)
        start(0)
        wait_until(lambda: role(0) == 5, 180, "A the primary")
        start(1)
        for t in threads:
            t.start()
        for _ in range(n):
            try:
                # the pair whole: the standby hears the primary, both writers acknowledged on the primary
                wait_until(lambda: 5 in (role(0), role(1)), 180, "a primary")
                at = 0 if role(0) == 5 else 1
                standby = modbus[1 - at]
                # 180 s: a station's process starts in a minute and more at load average 30
                try:
                    wait_until(lambda: (s := hsb(standby)) is not None and s[0] == 4 and s[1], 180,  # noqa: B023
                               "the pair whole")
                except SystemExit:
                    print(f"HSB of A and B (status, link up, lag): {hsb(modbus[0])}, {hsb(modbus[1])}")
                    raise
                time.sleep(0.5)
                wait_until(lambda: all(w.acked and w.acked[-1][1] == at for w in writers), 180,  # noqa: B023
                           "both writers on the primary")
                status = hsb(modbus[1 - at])
                lag.append(status[2] if status is not None else -1)
                procs[at].send_signal(signal.SIGKILL)
                dead = at
                killed, killed_wall = time.monotonic(), time.time()
                procs[at].wait()
                for w in writers:
                    wait_until(lambda w=w, dead=at: w.acked[-1][1] != dead, 180,
                               f"{w.name} writes to the new primary")
                    took[w.name].append(next(t for _v, i, t in w.acked if i != at and t > killed) - killed)
                killings.append((killed_wall, "AB"[1 - at]))
                start(at)  # the old primary back, as the standby
                dead, restarted = None, at
            except (SystemExit, KeyboardInterrupt) as e:  # the figures of the kills done so far, and why
                stopped = f" (stopped after {len(killings)}: {e or 'interrupted'})"
                if dead is not None:  # back, to forward what it committed before it was killed
                    start(dead)
                    with contextlib.suppress(SystemExit):
                        wait_until(lambda: role(dead) is not None, 180, "the killed station back")  # noqa: B023
                break
        else:  # the last one killed back, up as the standby, before the stop: it forwards its tail
            # then, and at its stop (a SIGTERM while it starts ends it before it forwards anything)
            with contextlib.suppress(SystemExit):
                wait_until(lambda i=restarted: (s := hsb(modbus[i])) is not None and s[0] == 4 and s[1], 180,
                           "the killed station back as the standby")
    finally:
        stop.set()
        for t in threads:
            if t.is_alive():
                t.join(30)
        for p in procs.values():
            p.terminate()
            p.wait(30)
    counts = applied(paths, since)
    led = 0  # kills after which the survivor journaled no takeover: it led already (a takeover of its
    for killed_wall, letter in killings:  # own while the primary stalled, between the check and the kill)
        after = [ts / 1000 - killed_wall for ts in takeovers(paths[letter]) if ts >= killed_wall * 1000 - 1]
        if after and min(after) < 10:
            took["journal"].append(min(after))
        else:
            led += 1
    pair = load_station(paths["A"]).redundancy
    assert pair is not None
    told = sum(len(journaled(paths[x], "%the partner took over from scan%")) for x in "AB")
    flips = sum(len(journaled(paths[x], "%primary -> standby: partner % is primary%")) for x in "AB")
    print(f"{len(killings)} SIGKILLs{stopped} of the primary process at NetSyncTime {TICK_MS} ms "
          f"(failover_after {pair.failover_after} = {pair.failover_after * TICK_MS} ms), "
          f"load average {os.getloadavg()[0]:.1f}:")
    for what, times in took.items():
        ms = [t * 1000 for t in times]
        until = "the journal record" if what == "journal" else f"the first {what} write acknowledged"
        print(f"  takeover, kill to {until}: p50 {statistics.median(ms):.0f} ms, max {max(ms):.0f} ms")
    for w, word in zip(writers, (MODBUS_WORD, OPCUA_WORD), strict=True):
        times = counts[word]
        values = [v for v, _i, _t in w.acked]
        lost = sum(1 for v in values if not times[v])
        twice = sum(1 for c in times.values() if c > 1)
        print(f"  {w.name}: {len(values)} writes acknowledged, lost {lost} (+ {w.behind} takeovers with the "
              f"new primary's word below the last acknowledged), applied twice {twice}")
    print(f"  the standby's lag at the kill: max {max(lag)} scans; kills with no takeover journaled by "
          f"the survivor (it had taken over already): {led}; takeovers of a live primary (told, it "
          f"followed): {told}; flip-backs (two primaries meeting): {flips}")
    if plant:
        c = plant_check(plant, paths)
        print(f"plant archive: {c.total} records of the pair, {c.missing} of the local archives missing, "
              f"{c.copies} records twice, {c.twice_in_a_row} alarm transitions twice in a row (doubled, "
              f"or one missing between), {c.unjournaled} writes applied and journaled by neither station")


@dataclass
class PlantCheck:
    total: int  # records of the pair in the plant archive
    missing: int  # records of the local archives not in it
    twice_in_a_row: int  # alarm transitions twice in a row (one doubled, or one missing between)
    copies: int  # records in it more than once (the same time, kind, source, number, value, text)
    unjournaled: int  # writes applied that no record says (a break in a word's chain of old -> new)


def plant_check(url: str, paths: dict[str, Path]) -> PlantCheck:
    """Records of both local archives missing from the plant archive, and records in it twice;
    writes applied and journaled by neither station: each writer writes 1, 2, 3... to its word,
    so its records' "old -> new" values chain up, and a break is an applied write whose record
    was lost (one the old primary applied, its standby held, and neither archived)."""
    import sqlite3

    import psycopg

    from registrar.plant.schema import PAIR_ID_BASE
    from registrar.schema import DAY_GLOB

    ours: set[int] = set()  # a record both stations hold (a takeover's) has one pid in both
    for letter, folder in paths.items():
        con = sqlite3.connect(load_station(folder).Archive)
        for (name,) in con.execute("SELECT name FROM sqlite_master WHERE type = 'table' AND name GLOB ?",
                                   (DAY_GLOB,)):
            ours |= {i + PAIR_ID_BASE[letter] if pid is None else pid
                     for i, pid in con.execute(f'SELECT id, pid FROM "{name}"')}
        con.close()
    with psycopg.connect(url) as pg:
        ids = {i for (i,) in pg.execute("SELECT id FROM records WHERE station = 'pair'")}
        alarms = pg.execute("SELECT source, number, type FROM records WHERE station = 'pair' "
                            "AND kind = 'alarm' ORDER BY ts, id").fetchall()
        copies = pg.execute("SELECT coalesce(sum(n - 1), 0) FROM (SELECT count(*) AS n FROM records "
                            "WHERE station = 'pair' GROUP BY ts, kind, source, number, value, text) c"
                            ).fetchone()[0]
        writes = pg.execute("SELECT number, text FROM records WHERE station = 'pair' AND kind = 'operator' "
                            "AND text LIKE 'write %%' AND number IN (%s, %s)",
                            (MODBUS_WORD, OPCUA_WORD)).fetchall()
    doubled = sum(1 for before, row in itertools.pairwise(alarms) if before == row)
    breaks = 0
    for word in (MODBUS_WORD, OPCUA_WORD):
        chain = sorted((int(new), int(old)) for number, text in writes if number == word
                       and (m := re.search(r": (\d+) -> (\d+)", text)) for old, new in [m.groups()])
        breaks += sum(1 for (before, _), (_, old) in itertools.pairwise(chain) if old != before)
    return PlantCheck(len(ids), len(ours - ids), doubled, int(copies), breaks)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=5.0)
    p.add_argument("--kills", type=int, default=20)
    p.add_argument("--plant", action="store_true", help="forward to a throwaway PostgreSQL cluster")
    p.add_argument("--serve", type=Path, help=argparse.SUPPRESS)  # a station of the pair (a child)
    p.add_argument("--modbus-port", type=int, help=argparse.SUPPRESS)
    p.add_argument("--opcua", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.serve is not None:
        serve(args.serve, args.modbus_port, args.opcua)
        return
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
