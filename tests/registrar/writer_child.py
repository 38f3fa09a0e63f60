"""Child process of the crash test: writes records without end and prints each committed total.

The parent kills it with SIGKILL at an arbitrary moment; every total printed here must be on disk.
"""

import sys
import time

from netplc.records import Record
from registrar.store import Store


def main(path: str) -> None:
    def committed(total: int) -> None:
        print(total, flush=True)

    store = Store(path, flush_interval=0.02, queue_size=10_000_000, on_commit=committed)  # never drops
    store.start()
    i = 0
    while True:
        store.put(Record(time.time(), "data", 1, 1, "04000", number=i, value=float(i)))
        i += 1
        if i % 200 == 0:
            time.sleep(0.001)


if __name__ == "__main__":
    main(sys.argv[1])
