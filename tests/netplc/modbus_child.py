"""Child process of the Modbus crash test: a NetPlc engine scanning every 10 ms, its records going
to a real archive, its memory served over Modbus TCP with everything writable. Prints the port,
then runs until the parent kills it with SIGKILL."""

import sys
import threading

from netplc.engine import Engine
from netplc.modbus import ModbusServer
from netplc.program import parse
from netplc.scheduler import ScanThread
from netplc.simulator import EngineMemory
from registrar.store import Store


def main(path: str) -> None:
    store = Store(path)
    store.start()
    engine = Engine(parse("TNA $03760\nJMP 0\n"), sink=store, tick=0.01)
    ScanThread(engine, 0.01).start()
    server = ModbusServer(EngineMemory(engine), sink=engine.sink)
    server.start()
    print(server.port, flush=True)
    threading.Event().wait()


if __name__ == "__main__":
    main(sys.argv[1])
