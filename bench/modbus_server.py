"""CPU per request and requests per second of NetPlc's Modbus TCP server at the pipelined ceiling,
against a bare asyncio protocol answering the same bytes, measured in the same run.

Each server runs alone in a child process (ours: a NetPlc engine's snapshot served by
netplc.modbus.server.ModbusServer with its default limits; the floor: an asyncio.Protocol that
reads the MBAP header of each request and answers a fixed 64-register PDU, doing nothing else).
This process is the client: one connection pipelines N "read 64 holding registers" requests as
fast as the server takes them, a thread counting the answer bytes. Server CPU per request is
the child's user + system time (Linux /proc) over the requests; the ratio is ours / the floor.
Runs alternate between the two servers; medians are printed.

    .venv/bin/python bench/modbus_server.py [--requests N] [--runs R]
    .venv/bin/python bench/modbus_server.py --flood 300000    # the write flood of issue 18
"""

from __future__ import annotations

import argparse
import asyncio
import os
import socket
import statistics
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REGISTERS = 64
ANSWER = 7 + 2 + 2 * REGISTERS  # MBAP, function code, byte count, data
TARGET_US, TARGET_RATE = 3.0, 100_000


def serve_ours() -> None:
    from netplc.engine import Engine
    from netplc.modbus import ModbusServer
    from netplc.program import parse
    from netplc.simulator import EngineMemory

    engine = Engine(parse("JMP 0\n"))
    for i in range(REGISTERS):
        engine.mem.set_word(0o4000 + 2 * i, 0x1234 + i)
    engine.scan()
    server = ModbusServer(EngineMemory(engine, ()))
    server.start()
    print(server.port, flush=True)
    sys.stdin.read()
    server.stop()


class Floor(asyncio.Protocol):
    """The yardstick: answers every whole request with the same 64 registers, nothing checked."""

    body = struct.pack(">HBBB", 3 + 2 * REGISTERS, 1, 3, 2 * REGISTERS) + bytes(2 * REGISTERS)

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport
        self.buf = bytearray()

    def data_received(self, data: bytes) -> None:
        buf = self.buf
        buf += data
        out = bytearray()
        pos, end, body = 0, len(buf), self.body
        while end - pos >= 12:
            out += buf[pos : pos + 4] + body
            pos += 12
        del buf[:pos]
        self.transport.write(out)  # type: ignore[attr-defined]


def serve_floor() -> None:
    async def run() -> None:
        loop = asyncio.get_running_loop()
        server = await loop.create_server(Floor, "127.0.0.1", 0)
        print(server.sockets[0].getsockname()[1], flush=True)
        await loop.run_in_executor(None, sys.stdin.read)
        server.close()

    asyncio.run(run())


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def hammer(port: int, requests: bytes, n: int, pid: int) -> tuple[float, float]:
    """(server CPU µs per request, requests per second) for n pipelined requests."""
    sock = socket.create_connection(("127.0.0.1", port))
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    expected = n * ANSWER
    got = [0]

    def count() -> None:
        while got[0] < expected:
            data = sock.recv(1 << 20)
            if not data:
                break
            got[0] += len(data)

    reader = threading.Thread(target=count)
    cpu0, t0 = cpu_seconds(pid), time.perf_counter()
    reader.start()
    sock.sendall(requests)
    reader.join()
    wall = time.perf_counter() - t0
    cpu = cpu_seconds(pid) - cpu0
    sock.close()
    if got[0] != expected:
        raise SystemExit(f"bench: {got[0]} of {expected} answer bytes")
    return 1e6 * cpu / n, n / wall


def flood(n: int) -> None:
    """Issue 18's write flood: n pipelined single-register writes from one client to a server with
    the default limits and write budget, its engine's records going to a real archive, the scans
    run back to back (a fake clock, 10 ms apart). Prints the longest scan, busy answers, records lost."""
    import tempfile

    from netplc.engine import Engine, FakeClock
    from netplc.modbus import ModbusServer
    from netplc.program import parse
    from netplc.simulator import EngineMemory
    from registrar.store import Store

    with tempfile.TemporaryDirectory() as tmp:
        store = Store(Path(tmp) / "journal.sqlite")
        store.start()
        clock = FakeClock()
        engine = Engine(parse("TNA $03760\nJMP 0\n"), clock=clock, sink=store)
        server = ModbusServer(EngineMemory(engine), sink=store)
        server.start()
        sock = socket.create_connection(("127.0.0.1", server.port))
        writes = b"".join(struct.pack(">HHHBBHH", i & 0xFFFF, 0, 6, 1, 6, 1024 + i % 1000, i & 0xFFFF)
                          for i in range(n))
        answers = {"done": 0, "busy": 0}

        def read() -> None:
            buf = b""
            while answers["done"] + answers["busy"] < n:
                data = sock.recv(1 << 20)
                if not data:
                    return
                buf += data
                while len(buf) >= 9 and len(buf) >= 6 + struct.unpack_from(">H", buf, 4)[0]:
                    end = 6 + struct.unpack_from(">H", buf, 4)[0]
                    answers["done" if buf[7] == 6 else "busy"] += 1
                    buf = buf[end:]

        reader = threading.Thread(target=read)
        reader.start()
        threading.Thread(target=sock.sendall, args=(writes,), daemon=True).start()
        longest, scans, t0 = 0.0, 0, time.monotonic()
        while reader.is_alive() and time.monotonic() - t0 < 300:
            t = time.perf_counter()
            clock.advance(0.1)
            engine.scan()
            longest = max(longest, 1000 * (time.perf_counter() - t))
            scans += 1
            time.sleep(0.01)
        server.stop()
        sock.close()
        store.close()
        print(f"flood: {n:,} pipelined writes: {answers['done']:,} done, {answers['busy']:,} busy "
              f"(exception 6) in {scans} scans; longest scan {longest:.1f} ms (budget "
              f"{engine.write_budget} writes per scan); archive records dropped {store.stats.dropped}")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--requests", type=int, default=300_000, help="pipelined requests per run")
    p.add_argument("--runs", type=int, default=5, help="runs per server (alternating)")
    p.add_argument("--flood", type=int, metavar="N", help="instead: N pipelined writes (issue 18's flood)")
    p.add_argument("--serve", choices=("ours", "floor"), help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.serve:
        (serve_ours if args.serve == "ours" else serve_floor)()
        return 0
    if args.flood:
        flood(args.flood)
        return 0
    n = args.requests
    requests = b"".join(struct.pack(">HHHBBHH", i & 0xFFFF, 0, 6, 1, 3, 1024, REGISTERS) for i in range(n))
    children = {name: subprocess.Popen([sys.executable, __file__, "--serve", name], cwd=ROOT,
                                       stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
                for name in ("ours", "floor")}
    results: dict[str, list[tuple[float, float]]] = {name: [] for name in children}
    try:
        ports = {name: int(c.stdout.readline()) for name, c in children.items()}  # type: ignore[union-attr]
        for name in children:  # warm up
            hammer(ports[name], requests[: 12 * 10_000], 10_000, children[name].pid)
        for _ in range(args.runs):
            for name, child in children.items():
                results[name].append(hammer(ports[name], requests, n, child.pid))
    finally:
        for child in children.values():
            assert child.stdin is not None
            child.stdin.close()
            child.wait(10)
    print(f"{os.cpu_count()} CPUs; {n:,} pipelined reads of {REGISTERS} registers per run, "
          f"{args.runs} runs each, one connection")
    med = {name: (statistics.median(r[0] for r in rs), statistics.median(r[1] for r in rs))
           for name, rs in results.items()}
    for name, rs in results.items():
        us = ", ".join(f"{r[0]:.2f}" for r in rs)
        print(f"{name:>6}: CPU {med[name][0]:.2f} us/request (runs {us}); "
              f"{med[name][1]:,.0f} requests/s")
    print(f"ratio ours / bare asyncio floor: CPU {med['ours'][0] / med['floor'][0]:.2f}x, "
          f"rate {med['ours'][1] / med['floor'][1]:.2f}x")
    print(f"target: <= {TARGET_US:g} us/request and >= {TARGET_RATE:,} requests/s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
