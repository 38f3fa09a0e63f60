"""Block reads per second, data age and NetPlc CPU use of the exchange, for K = 1, 8, 32 nodes.

K simulated CPU-165 nodes (netplc.simulator: engine + Modbus TCP server each) run in a separate
process; this process runs NetPlc: an engine on its scan thread whose program, for every node,
selects it with NODE and NREADs 64 bytes (32 registers) of its data memory on every scan, and the
exchange (one asyncio task per node on its own thread). Two runs per K:

- tick 100 ms (the default NetSyncTime): every node must be fully refreshed on every tick, i.e.
  K x 10 block reads per second with the data at most 1 tick old (age = scans from the NREAD that
  asked to the scan that first sees the data; 1 is the minimum);
- tick 1 ms: the program asks far more than the network can deliver, so the figure is the
  capacity of the whole exchange (target: at least 5,000 block reads per second), once with our
  lean Modbus TCP client (the exchange's default) and once with pymodbus's client.

CPU is this process's (NetPlc's) user+system time over wall time, 100 % = one core; "nodes CPU"
is the same for the process of the simulated nodes (Linux /proc), to show which side limits.

    .venv/bin/python bench/exchange.py [--seconds S] [--nodes 1,8,32]
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
TARGET_READS = 5000

# a node changes its data every scan, so a read is never answered from an idle memory
NODE_PROGRAM = "TNA $03760\nFON C:$03000 N:INCW S:$04100 D:$04000\nJMP 0\n"


def netplc_program(k: int) -> str:
    lines = []
    for i in range(k):
        local = 0o4000 + BLOCK * i  # 32 nodes x 64 bytes fill bank 0
        lines += ["TNA $03760", f"FON C:$0{0o2000 + 8 * i:o} N:NODE S:{i}",
                  "TNA $03760", f"FON C:$0{0o2004 + 8 * i:o} N:NREAD S:4000 D:$0{local:o} R:{BLOCK}"]
    return "\n".join([*lines, "JMP 0", ""])


def serve(k: int) -> None:
    """Child process: K simulated nodes; print their ports, run until stdin closes."""
    from netplc.simulator import Simulator

    sims = [Simulator(parse(NODE_PROGRAM, "node.stl"), tick=0.1) for _ in range(k)]
    for s in sims:
        s.start()
    print(json.dumps([s.port for s in sims]), flush=True)
    sys.stdin.read()
    for s in sims:
        s.stop()


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
        deadline = time.monotonic() + 5
        while not all(exchange.link_up(i) for i in range(len(ports))):
            if time.monotonic() > deadline:
                raise SystemExit("bench: not every node came up within 5 s")
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


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=3.0, help="measuring time per run (default 3)")
    p.add_argument("--nodes", default="1,8,32", help="node counts (default 1,8,32)")
    p.add_argument("--serve", type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.serve:
        serve(args.serve)
        return 0
    print(f"{os.cpu_count()} CPUs; block = {BLOCK} bytes (NREAD R:{BLOCK}); {args.seconds:g} s per run")
    print(f"{'K':>3} {'tick':>6} {'client':>8} {'reads/s':>9} {'per node/tick':>14} {'age mean':>9} "
          f"{'age max':>8} {'CPU %':>6} {'nodes CPU %':>8} {'errors':>6} {'scan max ms':>11}")
    for k in (int(x) for x in args.nodes.split(",")):
        child = subprocess.Popen([sys.executable, __file__, "--serve", str(k)], cwd=ROOT,
                                 stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        try:
            assert child.stdout is not None
            ports = json.loads(child.stdout.readline())
            for tick, lean in ((0.1, True), (0.001, True), (0.001, False)):
                r = measure(ports, tick, args.seconds, child.pid, lean)
                client = "lean" if lean else "pymodbus"
                print(f"{k:>3} {tick * 1000:>4g}ms {client:>8} {r['reads_per_s']:>9.0f} "
                      f"{r['per_node_per_tick']:>14.2f} {r['age_mean']:>9.2f} {r['age_max']:>8.0f} "
                      f"{r['cpu']:>6.0f} {r['nodes_cpu']:>8.0f} "
                      f"{r['errors']:>6.0f} {r['scan_max_ms']:>11.2f}", flush=True)
        finally:
            assert child.stdin is not None
            child.stdin.close()
            child.wait(10)
    print(f"target: K=32 at 100 ms: 1.00 read per node per tick, age 1; >= {TARGET_READS} block reads/s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
