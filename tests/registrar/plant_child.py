"""Child process of the plant-archive SIGKILL test: a station writing without end to its local
archive while its forwarder copies to PostgreSQL; it prints each forwarded total."""

import sys
import time

from netplc.records import Record
from registrar.plant.forward import Forwarder
from registrar.store import Store


def main(path: str, url: str) -> None:
    store = Store(path, flush_interval=0.01, queue_size=10_000_000)
    store.start()
    forwarder = Forwarder(path, url, "killed", interval=0.01, batch=3_000)
    forwarder.start()
    i = 0
    while True:
        store.put(Record(time.time(), "data", 1, 1, "04000", number=i, value=float(i)))
        i += 1
        if i % 200 == 0:
            time.sleep(0.001)
            print(forwarder.stats.forwarded, flush=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
