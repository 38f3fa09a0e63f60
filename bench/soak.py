"""A bounded soak of a whole station (issue 18): Modbus clients hammering its server, its node
killed and restarted every 20 s, the archive writing all along. Reports the longest scan, records
lost (must be 0), retentive saves, resident memory growth and open file descriptors at the end.

The station runs in this process exactly as `main.py --no-gui` runs it (app.station.runtime.Runtime on a
station folder written to a temporary directory): a 100 ms tick, a program that NREADs 64 bytes
of node 0 and NWRITEs 2 bytes back every scan and NSTOREs five values every scan (50 records/s),
its Modbus server with the default limits. Node 0 is a simulated CPU-165 in a child process,
killed with SIGKILL and started again on the same port every 20 s. The clients run in another
child process: two pipelining 64-register reads, one pipelining single-register writes (counting
those answered done and those answered busy, exception 6), and one that connects, sends garbage
and leaves, twice a second.

Records lost = records the archive dropped + Modbus writes answered done whose 'operator' record
is not in the archive. Memory and descriptors are compared with their values after a 10 s warm-up.

    .venv/bin/python bench/soak.py [--seconds 300]
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import socket
import sqlite3
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WARMUP = 10.0
KILL_EVERY = 20.0
BUSY = b"\x86\x06"  # exception 6 to a write: the queue of outside writes is full

PROGRAM = """\
TNA $03760
FON C:$02000 N:NODE S:0
TNA $03760
FON C:$02004 N:NREAD S:4000 D:$04000 R:64
TNA $03760
FON C:$02010 N:NWRITE S:$04200 D:4100 R:2
""" + "".join(f"TNA $03760\nFON C:$0{0o2020 + 4 * i:o} N:NSTORE S:$0{0o4000 + 2 * i:o} D:1 R:{i + 1}\n"
              for i in range(5)) + "JMP 0\n"
NODE = "TNA $03760\nFON C:$03000 N:INCW S:$04100 D:$04000\nJMP 0\n"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def open_fds() -> int:
    return len(os.listdir("/proc/self/fd"))


# --- the clients (child process) -----------------------------------------------------------------

def _answers(sock: socket.socket, n: int, buf: bytearray) -> list[bytes]:
    out: list[bytes] = []
    while len(out) < n:
        while len(buf) >= 7 and len(buf) >= 6 + struct.unpack_from(">H", buf, 4)[0]:
            length = struct.unpack_from(">H", buf, 4)[0]
            out.append(bytes(buf[7 : 6 + length]))
            del buf[: 6 + length]
        if len(out) >= n:
            break
        data = sock.recv(65536)
        if not data:
            raise ConnectionError("closed")
        buf += data
    return out


def clients(port: int, seconds: float) -> None:
    end = time.monotonic() + seconds
    counts = {"reads": 0, "writes_done": 0, "writes_busy": 0, "errors": 0, "garbage": 0}
    lock = threading.Lock()

    def add(key: str, n: int = 1) -> None:
        with lock:
            counts[key] += n

    def reader() -> None:
        request = b"".join(struct.pack(">HHHBBHH", i, 0, 6, 1, 3, 1024, 64) for i in range(16))
        while time.monotonic() < end:
            try:
                with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
                    buf = bytearray()
                    while time.monotonic() < end:
                        sock.sendall(request)
                        add("reads", sum(1 for a in _answers(sock, 16, buf) if a[0] == 3))
            except OSError:
                add("errors")
                time.sleep(0.1)

    def writer() -> None:
        value = 0
        while time.monotonic() < end:
            try:
                with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
                    buf = bytearray()
                    while time.monotonic() < end:
                        batch = b"".join(struct.pack(">HHHBBHH", i, 0, 6, 1, 6, 1024 + 128 + i,
                                                     (value + i) & 0xFFFF) for i in range(32))
                        value += 32
                        sock.sendall(batch)
                        for a in _answers(sock, 32, buf):
                            add("writes_done" if a[0] == 6 else "writes_busy" if a == BUSY else "errors")
            except OSError:
                add("errors")
                time.sleep(0.1)

    def garbage() -> None:
        rng = random.Random(1)
        while time.monotonic() < end:
            try:
                with socket.create_connection(("127.0.0.1", port), timeout=2) as sock:
                    sock.sendall(rng.randbytes(rng.randrange(1, 40)))
                add("garbage")
            except OSError:
                add("errors")
            time.sleep(0.5)

    threads = [threading.Thread(target=f) for f in (reader, reader, writer, garbage)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    print(json.dumps(counts), flush=True)


# --- the station (this process) ------------------------------------------------------------------

def write_station(folder: Path, node_port: int) -> None:
    (folder / "netplc.stl").write_text(PROGRAM, encoding="utf-8")
    (folder / "node.stl").write_text(NODE, encoding="utf-8")
    (folder / "station.toml").write_text(f"""\
NetPlcLoad = true
NetPlcProgram = "netplc.stl"
NetSyncTime = 100
Archive = "archive/journal.sqlite"

[modbus_server]
port = 0
writable = [["04000", "04777"]]

[[nodes]]
node = 0
endpoint = "tcp://127.0.0.1:{node_port}"
timeout = 0.3
retries = 1
backoff = 0.2
backoff_max = 1
""", encoding="utf-8")


def start_node(folder: Path, port: int) -> subprocess.Popen[bytes]:
    return subprocess.Popen([sys.executable, "main.py", "simulate", str(folder / "node.stl"), "--port",
                             str(port), "--tick", "100"], cwd=ROOT, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)


def modbus_writes_journaled(archive: Path) -> int:
    con = sqlite3.connect(archive)
    try:
        days = [n for (n,) in con.execute(
            "SELECT name FROM sqlite_master WHERE type = 'table' AND name GLOB '[0-9][0-9]_[0-9][0-9]_*'")]
        return sum(con.execute(f'SELECT count(*) FROM "{d}" WHERE kind = ? AND source LIKE ?',
                               ("operator", "modbus %")).fetchone()[0] for d in days)
    finally:
        con.close()


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=300.0, help="soak time after the warm-up (default 300)")
    p.add_argument("--clients", nargs=2, type=float, metavar=("PORT", "SECONDS"), help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.clients:
        clients(int(args.clients[0]), args.clients[1])
        return 0

    from app.station.config import load_station
    from app.station.runtime import Runtime
    from netplc.engine import ScanStats

    with tempfile.TemporaryDirectory(prefix="soak-") as tmp:
        folder = Path(tmp)
        node_port = free_port()
        write_station(folder, node_port)
        node = start_node(folder, node_port)
        runtime = Runtime(load_station(folder))
        runtime.start()
        assert runtime.modbus is not None and runtime.engine is not None and runtime.store is not None
        port = runtime.modbus.port
        total = WARMUP + args.seconds
        client = subprocess.Popen([sys.executable, __file__, "--clients", str(port), str(total)], cwd=ROOT,
                                  stdout=subprocess.PIPE, text=True)
        kills = 0
        try:
            time.sleep(WARMUP)
            runtime.engine.stats = ScanStats()
            rss0, fds0, t0 = rss_mb(), open_fds(), time.monotonic()
            assert runtime.retainer is not None
            saves0 = runtime.retainer.saves
            next_kill = t0 + KILL_EVERY
            while time.monotonic() - t0 < args.seconds:
                time.sleep(0.5)
                if time.monotonic() >= next_kill:
                    node.send_signal(signal.SIGKILL)
                    node.wait()
                    node = start_node(folder, node_port)
                    kills += 1
                    next_kill += KILL_EVERY
            rss1, fds1 = rss_mb(), open_fds()
            saves = runtime.retainer.saves - saves0  # one per scan with answered writes, at most
            out, _ = client.communicate(timeout=60)
            counts = json.loads(out.strip().splitlines()[-1])
            status = runtime.status()
        finally:
            if client.poll() is None:
                client.kill()
            runtime.stop()
            node.kill()
            node.wait()
        store = runtime._final_store
        dropped = store.dropped if store else -1
        journaled = modbus_writes_journaled(folder / "archive" / "journal.sqlite")
        unjournaled = max(0, counts["writes_done"] - journaled)
        print(f"soak: {args.seconds:g} s after a {WARMUP:g} s warm-up; node killed and restarted "
              f"{kills} times; {os.cpu_count()} CPUs")
        print(f"scan: max {status.scan_max_ms:.1f} ms, mean {status.scan_mean_ms:.2f} ms, "
              f"{status.overruns} overruns of the {status.tick_ms} ms tick in {status.scans} scans")
        print(f"clients: {counts['reads']:,} reads, {counts['writes_done']:,} writes answered done, "
              f"{counts['writes_busy']:,} answered busy (exception 6), "
              f"{counts['garbage']} garbage connections, {counts['errors']} client errors")
        print(f"archive: {store.committed if store else 0:,} records written; "
              f"records lost: {dropped + unjournaled} (dropped {dropped}, answered writes without a "
              f"record {unjournaled}; {journaled:,} Modbus writes journaled)")
        print(f"retentive memory: {saves:,} saves ({saves / args.seconds:.1f}/s), each before the "
              "writes of its scan were answered")
        print(f"memory: RSS {rss0:.1f} -> {rss1:.1f} MB ({rss1 - rss0:+.1f} MB); "
              f"open fds {fds0} -> {fds1}")
        return 0 if dropped + unjournaled == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
