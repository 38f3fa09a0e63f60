"""Registrar figures: sustained write rate, first filtered page and a downsampled series of a big day.

One day of 1,000,000 records goes through the real Store writer thread into a file on disk (90 %
NSTORE data: one dense source with half of the day, 19 others; 10 % NMSG messages with catalog
texts, a quarter of them alarms). The producer keeps the queue below half full, as a scan thread
would never outrun the disk for long; the rate counts from the first put to the end of close().
Then, from fresh read-only opens of that file: the first page of filtered queries (median of
several opens, open included) and a 10,000-point min/max series of the dense source.
Targets: >= 100,000 records/s sustained; first filtered page of a 1,000,000-record day < 100 ms.

    .venv/bin/python bench/archive.py [--records N] [--dir PATH]
"""

from __future__ import annotations

import argparse
import datetime as dt
import statistics
import tempfile
import threading
import time
from pathlib import Path

from netplc.records import Record
from registrar.catalog import Catalog, Message
from registrar.query import Archive, Filter
from registrar.store import Store

DAY = dt.date(2026, 3, 5)
CATALOG = Catalog({n: Message(n, n % 8, 2 if n % 4 == 0 else n % 2,
                              ("Авария насоса %d" if n % 4 == 0 else "Насос %d в работе") % n)
                   for n in range(1, 101)})
OPENS = 7


def records(n: int) -> list[Record]:
    start = dt.datetime(DAY.year, DAY.month, DAY.day).timestamp()
    step = 80_000 / n  # all within the local day
    out = []
    for i in range(n):
        ts = start + i * step
        if i % 10 == 9:
            number = 1 + (i // 10) % 100
            message = CATALOG.get(number)
            assert message is not None
            out.append(Record(ts, "message", message.grp, message.type, number=number))
        elif i % 2 == 0:
            out.append(Record(ts, "data", 1, 1, "04010", value=float(i % 4096)))
        else:
            src = i % 19
            source = f"0{0o4100 + 2 * src:o}"
            out.append(Record(ts, "data", 2 + src % 4, src % 5, source, value=float(i % 1000)))
    return out


def write(path: Path, batch: list[Record]) -> float:
    store = Store(path, catalog=CATALOG, queue_size=100_000, flush_interval=1.0)
    store.start()
    half = store.queue_size // 2
    t0 = time.perf_counter()
    done = threading.Event()

    def produce() -> None:
        for k in range(0, len(batch), 5_000):
            while store.stats.queued > half:
                time.sleep(0.001)
            for r in batch[k:k + 5_000]:
                store.put(r)
        done.set()

    producer = threading.Thread(target=produce)
    producer.start()
    producer.join()
    store.close()
    elapsed = time.perf_counter() - t0
    stats = store.stats
    assert stats.committed == len(batch) and stats.dropped == 0, stats
    return len(batch) / elapsed


def first_page(path: Path, flt: Filter) -> tuple[float, int]:
    times, n = [], 0
    for _ in range(OPENS):
        t0 = time.perf_counter()
        with Archive(path) as archive:
            n = len(archive.records(DAY, flt, limit=200))
        times.append(time.perf_counter() - t0)
    return statistics.median(times) * 1000, n


def series(path: Path) -> tuple[float, int, int]:
    times, n, total = [], 0, 0
    for _ in range(3):
        with Archive(path) as archive:
            t0 = time.perf_counter()
            ts, _ = archive.series(DAY, grp=1, type=1, source="04010", points=10_000)
            times.append(time.perf_counter() - t0)
            n = len(ts)
            total = archive.count(DAY, Filter(kinds={"data"}, source="04010"))
    return statistics.median(times) * 1000, n, total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=1_000_000)
    parser.add_argument("--dir", type=Path, default=None, help="where to write (default: a temp dir)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(dir=args.dir) as tmp:
        path = Path(tmp) / "journal.sqlite"
        batch = records(args.records)
        rate = write(path, batch)
        del batch
        print(f"registrar write, sustained through the writer thread: {rate:,.0f} records/s "
              f"({args.records:,} records, {path.stat().st_size / 1e6:.0f} MB)  target >= 100,000")
        cases = {
            "alarms (kind message, type >= 2)": Filter(kinds={"message"}, min_type=2),
            "messages of group 3": Filter(kinds={"message"}, grp=3),
            "text contains 'авария'": Filter(text="авария"),
            "group 99 (no match, key index)": Filter(grp=99),
            f"operator records (none among {args.records:,})": Filter(kinds={"operator"}),
            "text matching nothing (every text of the day read)": Filter(text="нет такого"),
        }
        for label, flt in cases.items():
            ms, n = first_page(path, flt)
            print(f"registrar first page, open + {label}: {ms:.1f} ms ({n} rows)  target < 100 ms")
        ms, n, total = series(path)
        print(f"registrar series: {total:,} points of one source -> {n:,} min/max points in {ms:.0f} ms")


if __name__ == "__main__":
    main()
