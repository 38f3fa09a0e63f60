"""Child process of the retentive test: a NetPlc program counting, saved by the Retainer.

It prints `restored <which> <word> <counter>` once, then `count <word> <counter>` every 50 ms;
SIGTERM stops it cleanly (`stopped <word> <counter>`), SIGKILL does not.
"""

import signal
import sys
import threading

from netplc.engine import Engine
from netplc.program import parse
from netplc.records import ListSink
from netplc.scheduler import ScanThread
from registrar.retain import Retainer

# The word 04000 counts every scan; the counter at 03000 counts the 0.1 s generator's edges.
PROGRAM = """
FON C:$02000 N:INCW S:$04002 D:$04000
TNA $03750
CTR C:$03000 N:255
JMP 0
"""
TICK = 0.02


def main(path: str) -> None:
    engine = Engine(parse(PROGRAM), tick=TICK, sink=ListSink())
    retainer = Retainer(path, engine)

    def state() -> str:
        return f"{engine.snapshot.get_word(0o4000)} {engine.ctr_values[0o3000]}"

    used = retainer.restore()
    print("restored", used, state(), flush=True)
    scan = ScanThread(engine)
    scan.start()
    retainer.start(interval=1.0)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    while not stop.wait(0.05):
        print("count", state(), flush=True)
    scan.stop()
    retainer.stop()
    print("stopped", state(), flush=True)


if __name__ == "__main__":
    main(sys.argv[1])
