"""A simulated CPU-165 node: the NetPlc engine running a CPU-165 program on its tick, served over
Modbus TCP, or Modbus RTU on a serial port, with the cpu165 profile and all of its memory writable
(docs/architecture.md section 1).

It is what a user points NetPlc at before the plant exists, what the demo station embeds, and
what the exchange tests and benchmark talk to. It has no exchange of its own: a CPU-165 answers
the network, it does not ask it.

    python main.py simulate PROGRAM.stl [--symbols F] [--host H] [--port P] [--unit U] [--tick MS]
    python main.py simulate PROGRAM.stl --serial "rtu:///dev/ttyUSB0?baudrate=19200&parity=E" ...
    python -m netplc.simulator PROGRAM.stl ...
"""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Iterable

from netplc import interruptible
from netplc.engine import Engine
from netplc.modbus import (
    ALL_MEMORY,
    APPLIED,
    BUSY,
    DEVICE_FAILURE,
    Done,
    Endpoint,
    MemoryServed,
    MemoryWrite,
    ModbusServer,
    parse_endpoint,
)
from netplc.program import Program, ProgramError, load_program
from netplc.records import Record, RecordSink
from netplc.scheduler import ScanThread


class EngineMemory(MemoryServed):
    """A node's memory served straight from its engine. A CPU-165 has no station and so no command
    layer: a write goes to the engine's bounded queue of outside writes (exception 6 when it is
    full), applied at the start of a scan and journaled by the engine naming the peer
    (`modbus 127.0.0.1:40686`), and is answered once that record is durable."""

    def __init__(self, engine: Engine, writable: Iterable[tuple[int, int]] = ALL_MEMORY) -> None:
        super().__init__(engine, writable)
        self.engine = engine

    def take(self, change: MemoryWrite, peer: str, done: Done) -> int | None:
        user = f"modbus {peer}"
        engine, first = self.engine, change.first
        if change.bits is not None:
            apply = (engine.bit_writer(first, change.bits[0], user) if len(change.bits) == 1
                     else engine.bits_writer(first, change.bits, user))
        elif len(change.data) == 2:
            apply = engine.word_writer(first, int.from_bytes(change.data, "little"), user)
        else:
            apply = engine.bytes_writer(first, change.data, user)
        if engine.command(apply, user, lambda ok: done(APPLIED if ok else DEVICE_FAILURE)):
            return None
        return BUSY


class ConsoleSink:
    """The simulator's journal when it runs on its own: the 'system' records (a serial port that
    failed and works again, refused connections) on stderr; its writes are not worth a line each."""

    def put(self, record: Record) -> None:
        if record.kind == "system":
            print(f"simulate: {record.text}", file=sys.stderr, flush=True)


class Simulator:
    def __init__(self, program: Program, host: str = "127.0.0.1", port: int = 0, unit: int | None = 1,
                 tick: float = 0.1, sink: RecordSink | None = None, serial: Endpoint | None = None) -> None:
        self.engine = Engine(program, tick=tick, sink=sink)
        self.scan = ScanThread(self.engine, tick, name="cpu165-sim-scan")
        self.server = ModbusServer(EngineMemory(self.engine), host, port, unit=unit, serial=serial,
                                   sink=self.engine.sink)

    @property
    def port(self) -> int:
        return self.server.port

    def start(self) -> None:
        self.scan.start()
        try:
            self.server.start()
        except Exception:
            self.scan.stop()
            raise

    def stop(self) -> None:
        self.server.stop()
        self.scan.stop()


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="simulate",
                                description="run a simulated CPU-165 node over Modbus TCP or RTU")
    p.add_argument("program", help="CPU-165 program (.stl)")
    p.add_argument("--symbols", help="symbols.csv (name,address,comment)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=502, help="TCP port (default 502; 0 = any free port)")
    p.add_argument("--serial", metavar="ENDPOINT",
                   help="answer as a Modbus RTU slave on this serial port instead of TCP: "
                        "rtu:///dev/ttyUSB0?baudrate=19200&parity=E (COM3 on Windows: rtu://COM3)")
    p.add_argument("--unit", type=int, default=1, help="Modbus unit id to answer (default 1)")
    p.add_argument("--tick", type=int, default=100, help="scan tick in ms (default 100)")
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if not 1 <= args.tick <= 60_000:
        print(f"simulate: --tick {args.tick}: expected 1-60000 ms", file=sys.stderr)
        return 2
    if not 0 <= args.unit <= 255 or not 0 <= args.port <= 65535:
        print("simulate: --unit takes 0-255 and --port 0-65535", file=sys.stderr)
        return 2
    serial = None
    if args.serial is not None:
        try:
            serial = parse_endpoint(args.serial)
        except ValueError as e:
            print(f"simulate: --serial: {e}", file=sys.stderr)
            return 2
        if serial.scheme != "rtu":
            print(f"simulate: --serial {args.serial!r}: expected an rtu:// endpoint", file=sys.stderr)
            return 2
    try:
        program = load_program(args.program, args.symbols)
    except ProgramError as e:
        print(e, file=sys.stderr)
        return 2
    except OSError as e:
        print(f"simulate: {e}", file=sys.stderr)
        return 2
    # Ctrl-C and SIGTERM stop the node, also where it was started with SIGINT ignored (a job a
    # script put in the background inherits that, and so did the suite's simulators)
    stop = interruptible.Flag()  # raised by the signal handlers: no lock (netplc/interruptible.py)
    previous = {s: signal.signal(s, lambda *_: stop.set()) for s in (signal.SIGINT, signal.SIGTERM)}
    sim = Simulator(program, args.host, args.port, args.unit, args.tick / 1000.0, sink=ConsoleSink(),
                    serial=serial)
    where = f"{args.host}:{args.port}" if serial is None else serial.device
    try:
        try:
            sim.start()
        except OSError as e:
            print(f"simulate: cannot {'listen on' if serial is None else 'open'} {where}: {e}",
                  file=sys.stderr)
            return 1
        if serial is None:
            served = f"Modbus TCP on {args.host}:{sim.port}"
        else:
            served = (f"Modbus RTU on {serial.device} ({serial.baudrate} baud, "
                      f"{serial.bytesize}{serial.parity}{serial.stopbits})")
        try:
            print(f"simulated CPU-165 node: {args.program} every {args.tick} ms, {served} unit {args.unit} "
                  "(Ctrl-C stops)", flush=True)
            interruptible.wait(stop)
        finally:
            sim.stop()
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return 0


if __name__ == "__main__":
    sys.exit(main())
