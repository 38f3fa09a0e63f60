"""Registrar figures: sustained write rate, first filtered page and a downsampled series of a big day.

One day of 1,000,000 records goes through the real Store writer thread into a file on disk (90 %
NSTORE data: one dense source with half of the day, 19 others; 10 % NMSG messages with catalog
texts, a quarter of them alarms). The producer keeps the queue below half full, as a scan thread
would never outrun the disk for long; the rate counts from the first put to the end of close().
Then, from fresh read-only opens of that file: the first page of filtered queries (median of
several opens, open included) and a 10,000-point min/max series of the dense source.
Yardsticks in the same run, interleaved with the Store's runs (medians of --rounds): raw
executemany of the same rows (built beforehand, texts resolved) into the same schema, one
transaction per 50,000 rows, each followed by the statements that keep the trigram text index and
the per-minute summary (what the Store runs); and, for comparison, into the day table and its two
indexes alone (the schema before them).
Targets: >= 100,000 records/s sustained and >= 0.75x the yardstick; first filtered page of a
1,000,000-record day < 100 ms, of a text search on a 10,000,000-record day < 100 ms; a series of
one source to 10,000 points on a 10,000,000-record day < 300 ms.

    .venv/bin/python bench/archive.py [--records N] [--rounds N] [--dir PATH]
"""

from __future__ import annotations

import argparse
import datetime as dt
import sqlite3
import statistics
import tempfile
import threading
import time
from pathlib import Path

from netplc.records import Record
from registrar.catalog import Catalog, Message
from registrar.query import Archive, Filter
from registrar.schema import DAY_COLUMNS_SQL, aux_fill_sql, aux_sql, index_sql, table_name
from registrar.store import BATCH_MAX, Store

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


def write(path: Path, batch: list[Record]) -> tuple[float, float]:
    """Records/s and CPU seconds per record (all threads: on a shared machine the steadier one)."""
    store = Store(path, catalog=CATALOG, queue_size=100_000, flush_interval=1.0)
    store.start()
    half = store.queue_size // 2
    t0, cpu = time.perf_counter(), time.process_time()
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
    elapsed, cpu = time.perf_counter() - t0, time.process_time() - cpu
    stats = store.stats
    assert stats.committed == len(batch) and stats.dropped == 0, stats
    return len(batch) / elapsed, cpu / len(batch)


def raw_executemany(path: Path, batch: list[Record], aux: bool) -> tuple[float, float]:
    """The yardstick: the rows as the Store would build them, inserted by plain executemany (and
    with `aux` the text index and summary statements after each batch)."""
    rows = [(round(r.ts * 1000), r.kind, r.grp, r.type, r.source, r.number, r.value,
             CATALOG.text_for(r.number) if r.kind == "message" and r.number is not None else r.text)
            for r in batch]
    con = sqlite3.connect(path, isolation_level=None)
    con.execute("PRAGMA journal_mode=WAL")
    con.execute("PRAGMA synchronous=NORMAL")
    table = table_name(DAY)
    con.execute(f'CREATE TABLE "{table}" {DAY_COLUMNS_SQL}')
    for sql in index_sql(table) + (aux_sql(table) if aux else []):
        con.execute(sql)
    fill = aux_fill_sql(table) if aux else []
    t0, cpu = time.perf_counter(), time.process_time()
    for k in range(0, len(rows), BATCH_MAX):
        con.execute("BEGIN IMMEDIATE")
        con.executemany(f'INSERT INTO "{table}" (ts, kind, grp, type, source, number, value, text) '
                        "VALUES (?, ?, ?, ?, ?, ?, ?, ?)", rows[k:k + BATCH_MAX])
        for sql in fill:
            con.execute(sql, (k,))
        con.execute("COMMIT")
    rate, cpu = len(rows) / (time.perf_counter() - t0), (time.process_time() - cpu) / len(rows)
    con.close()
    for suffix in ("", "-wal", "-shm"):
        Path(f"{path}{suffix}").unlink(missing_ok=True)
    return rate, cpu


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
    parser.add_argument("--rounds", type=int, default=3, help="interleaved write runs (medians)")
    parser.add_argument("--dir", type=Path, default=None, help="where to write (default: a temp dir)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(dir=args.dir) as tmp:
        path = Path(tmp) / "journal.sqlite"
        batch = records(args.records)
        raw = Path(tmp) / "raw.sqlite"
        same, plain, rates = [], [], []
        for k in range(args.rounds):
            same.append(raw_executemany(raw, batch, True))
            plain.append(raw_executemany(raw, batch, False))
            if k:
                for suffix in ("", "-wal", "-shm"):
                    Path(f"{path}{suffix}").unlink(missing_ok=True)
            rates.append(write(path, batch))
        del batch
        cpus = {name: statistics.median(c for _r, c in runs) * 1e6
                for name, runs in (("store", rates), ("same", same), ("plain", plain))}
        rates, same, plain = ([r for r, _c in runs] for runs in (rates, same, plain))
        rate, same_m, plain_m = (statistics.median(x) for x in (rates, same, plain))
        print(f"registrar write, sustained through the writer thread: {rate:,.0f} records/s "
              f"({args.records:,} records, {path.stat().st_size / 1e6:.0f} MB; median of "
              f"{', '.join(f'{r:,.0f}' for r in rates)})  target >= 100,000")
        print(f"registrar write yardstick, raw executemany into the same schema (text index and "
              f"summary kept by the same statements): {same_m:,.0f} records/s (median of "
              f"{', '.join(f'{r:,.0f}' for r in same)}): the Store is {rate / same_m:.2f}x  target >= 0.75x")
        print(f"registrar write, raw executemany into the day table and its two indexes alone: "
              f"{plain_m:,.0f} records/s (median of {', '.join(f'{r:,.0f}' for r in plain)}): "
              f"the Store is {rate / plain_m:.2f}x of that")
        print(f"registrar write, CPU per record (medians): Store {cpus['store']:.2f} us, raw into the "
              f"same schema {cpus['same']:.2f} us ({cpus['same'] / cpus['store']:.2f}x), raw into the "
              f"table alone {cpus['plain']:.2f} us ({cpus['plain'] / cpus['store']:.2f}x)")
        cases = {
            "alarms (kind message, type >= 2)": Filter(kinds={"message"}, min_type=2),
            "messages of group 3": Filter(kinds={"message"}, grp=3),
            "text contains 'авария'": Filter(text="авария"),
            "group 99 (no match, key index)": Filter(grp=99),
            f"operator records (none among {args.records:,})": Filter(kinds={"operator"}),
            "text matching nothing (trigram index)": Filter(text="нет такого"),
        }
        for label, flt in cases.items():
            ms, n = first_page(path, flt)
            print(f"registrar first page, open + {label}: {ms:.1f} ms ({n} rows)  target < 100 ms")
        ms, n, total = series(path)
        print(f"registrar series: {total:,} points of one source -> {n:,} min/max points in {ms:.0f} ms"
              f"  target < 300 ms")


if __name__ == "__main__":
    main()
