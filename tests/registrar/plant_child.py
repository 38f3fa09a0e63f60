"""Child process of the plant-archive SIGKILL test: it imports once, then for each line on its
stdin forks a station writing without end to its local archive while its forwarder copies to
PostgreSQL (`pid N` first, then each forwarded total). The test kills the station with SIGKILL;
this process reaps it before it forks the next, so a restart is a fork and not a second of an
interpreter's imports."""

import os
import sys
import time

from netplc.records import Record
from registrar.plant.forward import Forwarder
from registrar.store import Store


def station(path: str, url: str) -> None:
    store = Store(path, flush_interval=0.01, queue_size=10_000_000)
    store.start()
    forwarder = Forwarder(path, url, "killed", interval=0.01, batch=600)
    forwarder.start()
    i = 0
    while True:
        store.put(Record(time.time(), "data", 1, 1, "04000", number=i, value=float(i)))
        i += 1
        if i % 200 == 0:
            time.sleep(0.001)
            print(forwarder.stats.forwarded, flush=True)


def main(path: str, url: str) -> None:
    running = 0
    for _ in sys.stdin:
        if running:
            os.waitpid(running, 0)  # the station killed before it starts again
        running = os.fork()
        if running == 0:
            try:
                station(path, url)
            finally:
                os._exit(1)
        print("pid", running, flush=True)
    if running:
        os.waitpid(running, 0)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
