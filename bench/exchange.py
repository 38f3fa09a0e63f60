"""Block reads per second, data age and NetPlc CPU use of the exchange, for K = 1 ... 256 nodes.

K simulated CPU-165 nodes (an engine + a Modbus TCP server each, all served by one selector
thread, netplc/modbus/reactor.py, and scanned by one thread, each every 100 ms, spread over the
tick) run in a separate process; this process runs NetPlc: an engine on its scan thread whose
program, for every node, selects it with NODE and NREADs 64 bytes (32 registers) of its data
memory on every scan, and the exchange (its Modbus TCP thread: one epoll selector over the nodes'
non-blocking sockets, a request in flight on every node at once). Runs per K:

- tick 100 ms (the default NetSyncTime): every node must be fully refreshed on every tick, i.e.
  K x 10 block reads per second with the data 1 scan old (age = scans from the NREAD that
  asked to the scan that first sees the data; 1 is the minimum);
- tick 1 ms: the program asks far more than the network can deliver, so the figure is the
  capacity of the whole exchange (target: at least 10,000 block reads per second at every K, in
  every round), with our lean Modbus TCP client (the exchange's default), and for K <= 32 once
  more with pymodbus's client.

The yardstick, measured interleaved with the 1 ms runs (ROUNDS rounds, each an exchange run then
a yardstick run of the same length on the same nodes, so both see the same load of the machine),
is the simplest client there is doing the same work: one thread, blocking sockets, the same
requests (the exchange's own frame for the block, transaction id patched) to the same nodes
round-robin, each answer checked as the exchange checks it (transaction id, unit, function, byte
count) and its registers byte-swapped into the same place of a NetPlc memory. It does the same
reads and nothing else, so NetPlc's CPU per read (scan + exchange, the whole process: the program
asking every scan is part of NetPlc's way of reading) over its CPU per read is what that way
costs (target: at most 2x in every round); median and worst of the rounds. It is fair to the
yardstick in the other direction too: one request at a time, it never waits for a scan, so its
reads/s is the nodes' answer rate to a client that asks as soon as it has an answer.

The program never touches the special bits and bytes: the NREADs' coils are I/O bits 00000-01777
(4 per node: the link bit of node i is 4i+1), NODE shares one coil at 02000, and the local
blocks fill the data banks in order, 32 to a bank, leaving 077700-077777 (clock, presence list)
alone; 256 blocks of 64 bytes would need all 16 KB, so node 255 shares node 0's block.

CPU is this process's (NetPlc's) user+system time over wall time, 100 % = one core; "nodes CPU"
is the same for the process of the simulated nodes (Linux /proc), to show which side limits.

    .venv/bin/python bench/exchange.py [--seconds S] [--nodes 1,8,32,128,256]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from netplc.engine import Engine
from netplc.exchange import Exchange, NodeConfig
from netplc.program import parse
from netplc.scheduler import ScanThread

ROOT = Path(__file__).resolve().parents[1]
BLOCK = 64
TARGET_READS = 10_000
TARGET_CPU = 2.0  # NetPlc's CPU per read over the blocking client's
ROUNDS = 3
MAX_NODES = 256

# a node changes its data every scan, so a read is never answered from an idle memory
NODE_PROGRAM = "TNA $03760\nFON C:$03000 N:INCW S:$04100 D:$04000\nJMP 0\n"


def local_block(i: int) -> int:
    """Where node i's block lands: 32 blocks to a bank, in bank order, below 077700."""
    slots = [bank * 0o10000 + 0o4000 + BLOCK * j for bank in range(8) for j in range(32)]
    slots = [a for a in slots if a + BLOCK <= 0o77700]
    return slots[i % len(slots)]


def netplc_program(k: int) -> str:
    lines = []
    for i in range(k):
        lines += ["TNA $03760", f"FON C:$02000 N:NODE S:{i}",
                  "TNA $03760", f"FON C:$0{4 * i:o} N:NREAD S:4000 D:$0{local_block(i):o} R:{BLOCK}"]
    return "\n".join([*lines, "JMP 0", ""])


def serve(k: int) -> None:
    """Child process: K simulated nodes; print their ports, run until stdin closes."""
    import threading

    from netplc.engine import Engine
    from netplc.modbus import ModbusServer, Reactor
    from netplc.simulator import EngineMemory

    reactor = Reactor("nodes")
    reactor.start()
    engines = [Engine(parse(NODE_PROGRAM, "node.stl"), tick=0.1) for _ in range(k)]
    servers = [ModbusServer(EngineMemory(e), reactor=reactor) for e in engines]
    for s in servers:
        s.start()
    stop = threading.Event()

    def scan() -> None:  # each node every 100 ms, spread over the tick as separate devices would be
        while not stop.is_set():
            for e in engines:
                e.scan()
                stop.wait(0.1 / k)

    threading.Thread(target=scan, daemon=True).start()
    print(json.dumps([s.port for s in servers]), flush=True)
    sys.stdin.read()
    stop.set()
    for s in servers:
        s.stop()
    reactor.stop()


def cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of a process (Linux /proc; 0 elsewhere)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def measure(ports: list[int], tick: float, seconds: float, child: int, lean: bool) -> dict[str, float]:
    nodes = [NodeConfig(i, f"tcp://127.0.0.1:{p}", timeout=1.0) for i, p in enumerate(ports)]
    exchange = Exchange(nodes, lean=lean)
    engine = Engine(parse(netplc_program(len(ports))), tick=tick)
    exchange.attach(engine)
    exchange.start()
    scan = ScanThread(engine, tick)
    scan.start()
    try:
        deadline = time.monotonic() + 10
        while not all(exchange.link_up(i) for i in range(len(ports))):
            if time.monotonic() > deadline:
                raise SystemExit("bench: not every node came up within 10 s")
            time.sleep(0.01)
        time.sleep(0.2)
        for s in exchange.stats.values():
            s.age_max = 0
        reads0 = sum(s.reads for s in exchange.stats.values())
        errors0 = sum(s.errors for s in exchange.stats.values())
        scans0, cpu0, t0 = engine.stats.count, time.process_time(), time.monotonic()
        child0 = cpu_seconds(child)
        ages: list[int] = []
        while time.monotonic() - t0 < seconds:
            time.sleep(0.05)
            ages += [s.age for s in exchange.stats.values()]
        wall = time.monotonic() - t0
        cpu = time.process_time() - cpu0
        child_cpu = cpu_seconds(child) - child0
        reads = sum(s.reads for s in exchange.stats.values()) - reads0
        return {
            "reads_per_s": reads / wall,
            "per_node_per_tick": reads / len(ports) / ((engine.stats.count - scans0) or 1),
            "age_mean": sum(ages) / len(ages),
            "age_max": max(s.age_max for s in exchange.stats.values()),
            "cpu": 100.0 * cpu / wall,
            "nodes_cpu": 100.0 * child_cpu / wall,
            "errors": sum(s.errors for s in exchange.stats.values()) - errors0,
            "scan_max_ms": engine.stats.max_ms,
        }
    finally:
        scan.stop()
        exchange.stop()


def blocking_yardstick(ports: list[int], seconds: float) -> tuple[float, float]:
    """(reads/s, CPU us per read) of the simplest client there is doing the exchange's work: one
    thread, blocking sockets, each node's 64-byte read round-robin, the answer checked as the
    exchange checks it (transaction id, unit, function, byte count) and its data byte-swapped into
    the same place of a NetPlc memory."""
    import socket

    from netplc.memory import Memory
    from netplc.modbus import Frame, answer_data, locate

    block = locate("cpu165", "holding", 0o4000, BLOCK)
    frame = Frame.read(1, block.table, block.address, block.count)
    mem = Memory()
    socks = [socket.create_connection(("127.0.0.1", p)) for p in ports]
    for sock in socks:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    locals_ = [local_block(i) for i in range(len(ports))]
    size = 9 + 2 * block.count
    reads, tid, cpu0, t0 = 0, 0, time.process_time(), time.monotonic()
    while time.monotonic() - t0 < seconds:
        for sock, local in zip(socks, locals_, strict=True):
            tid = tid % 0xFFFF + 1
            sock.sendall(frame.stamped(tid))
            data = sock.recv(size)
            while len(data) < size:
                data += sock.recv(size - len(data))
            assert data[0] << 8 | data[1] == tid
            mem.write(local, block.decode_wire(answer_data(frame, data, 0, size)))
            reads += 1
    wall, cpu = time.monotonic() - t0, time.process_time() - cpu0
    for sock in socks:
        sock.close()
    return reads / wall, 1e6 * cpu / reads


def row(k: int, tick: float, client: str, r: dict[str, float]) -> str:
    return (f"{k:>3} {tick * 1000:>4g}ms {client:>8} {r['reads_per_s']:>9.0f} "
            f"{r['per_node_per_tick']:>14.2f} "
            f"{r['age_mean']:>9.2f} {r['age_max']:>8.0f} {r['cpu']:>6.0f} {r['nodes_cpu']:>8.0f} "
            f"{r['errors']:>6.0f} {r['scan_max_ms']:>11.2f}")


def compare(k: int, ports: list[int], seconds: float, child: int) -> None:
    """The 1 ms runs of the lean client and the yardstick, alternating, ROUNDS of each."""
    rates, ratios = [], []
    for _ in range(ROUNDS):
        r = measure(ports, 0.001, seconds / ROUNDS, child, True)
        print(row(k, 0.001, "lean", r), flush=True)
        netplc_us = 1e4 * r["cpu"] / r["reads_per_s"]
        rate, us = blocking_yardstick(ports, seconds / ROUNDS)
        rates.append(r["reads_per_s"])
        ratios.append(netplc_us / us)
        print(f"{'':>3} yardstick: blocking-socket client {rate:>9.0f} reads/s, {us:.0f} us CPU/read; "
              f"NetPlc (scan + exchange) {netplc_us:.0f} us CPU/read = {ratios[-1]:.2f}x", flush=True)
    ratios.sort()
    print(f"{k:>3} at 1 ms over {ROUNDS} rounds: reads/s median {sorted(rates)[ROUNDS // 2]:.0f}, worst "
          f"{min(rates):.0f}; CPU per read / the yardstick's median {ratios[ROUNDS // 2]:.2f}x, worst "
          f"{ratios[-1]:.2f}x", flush=True)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=3.0, help="measuring time per run (default 3)")
    p.add_argument("--nodes", default="1,8,32,128,256", help=f"node counts, up to {MAX_NODES} "
                   "(default 1,8,32,128,256)")
    p.add_argument("--serve", type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.serve:
        serve(args.serve)
        return 0
    print(f"{os.cpu_count()} CPUs; block = {BLOCK} bytes (NREAD R:{BLOCK}); {args.seconds:g} s per run")
    print(f"{'K':>3} {'tick':>6} {'client':>8} {'reads/s':>9} {'per node/tick':>14} {'age mean':>9} "
          f"{'age max':>8} {'CPU %':>6} {'nodes CPU %':>8} {'errors':>6} {'scan max ms':>11}")
    counts = [int(x) for x in args.nodes.split(",")]
    if not all(1 <= k <= MAX_NODES for k in counts):
        p.error(f"--nodes: each count must be 1-{MAX_NODES}")
    for k in counts:
        child = subprocess.Popen([sys.executable, __file__, "--serve", str(k)], cwd=ROOT,
                                 stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        try:
            assert child.stdout is not None
            ports = json.loads(child.stdout.readline())
            for tick, lean in ((0.1, True), (0.001, True), (0.001, False))[: 3 if k <= 32 else 2]:
                client = "lean" if lean else "pymodbus"
                if tick == 0.001 and lean:
                    compare(k, ports, args.seconds, child.pid)
                    continue
                r = measure(ports, tick, args.seconds, child.pid, lean)
                print(row(k, tick, client, r), flush=True)
        finally:
            assert child.stdin is not None
            child.stdin.close()
            child.wait(10)
    print(f"target: at 100 ms 1.00 read per node per tick, age 1; >= {TARGET_READS:,} block reads/s at 1 ms "
          f"and CPU per read <= {TARGET_CPU:g}x the blocking client's, in every round")
    return 0


if __name__ == "__main__":
    sys.exit(main())
