"""Plant archive figures: stations forwarding into one PostgreSQL, and a big day read back.

1. N simulated stations (processes), each writing R records/s through its real Store into a local
   SQLite file while its Forwarder copies to the plant archive; the run lasts S seconds and then
   every forwarder is let catch up. Printed: records forwarded per second in total (from the first
   put to the last station caught up), forwarding lag p99 (sampled every 0.1 s in each station:
   the age of the oldest record not yet in PostgreSQL), and as yardstick one process's raw binary
   COPY of the same rows into the same schema in the same run.
2. One station's day of D records made in the server (generate_series, the bench/archive.py mix:
   90 % data, 10 % messages), then the first page of filtered queries from a fresh read-only open
   (median of several).
Targets: >= 100,000 records/s forwarded in total; first filtered page of a 10 M-record day < 200 ms.

    .venv/bin/python bench/plant_archive.py [--stations 8] [--rate 10000] [--seconds 10]
        [--day-records 10000000] [--url postgresql://...]   (default: a throwaway local cluster)
"""

from __future__ import annotations

import argparse
import datetime as dt
import multiprocessing as mp
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from netplc.records import Record  # noqa: E402
from registrar.plant import schema as pg  # noqa: E402
from registrar.plant.forward import Forwarder  # noqa: E402
from registrar.query import Archive, Filter  # noqa: E402
from registrar.store import Store  # noqa: E402

OPENS = 7
DAY = dt.date(2026, 3, 5)


def station(name: str, folder: str, url: str, rate: int, seconds: float, backlog: bool,
            out: mp.Queue) -> None:
    """backlog: the records are all in the local archive before forwarding starts (the plant
    archive was away), so the figure is what the forwarders can do, not what they are offered."""
    store = Store(Path(folder) / name / "journal.sqlite", flush_interval=0.1, queue_size=1_000_000)
    store.start()
    forwarder = Forwarder(store.path, url, name, interval=0.05)
    if backlog:
        for i in range(round(rate * seconds)):
            store.put(Record(time.time(), "data", 1 + i % 4, 1, f"0{0o4100 + i % 40:o}", value=float(i)))
        store.close()
        t0 = time.time()
        forwarder.start()
        while forwarder.stats.forwarded < store.committed:
            time.sleep(0.01)
        done = time.time()
        forwarder.close()
        out.put((name, t0, done, store.committed, forwarder.stats.forwarded, store.stats.dropped, [0.0]))
        return
    forwarder.start()
    lags: list[float] = []
    step = rate // 10
    t0 = time.time()
    i = 0
    while (now := time.time()) < t0 + seconds:
        for _ in range(step):
            store.put(Record(now, "data", 1 + i % 4, 1, f"0{0o4100 + i % 40:o}", value=float(i)))
            i += 1
        lags.append(forwarder.stats.lag)
        time.sleep(max(0.0, t0 + i / rate - time.time()))
    store.close()
    while forwarder.stats.forwarded < store.committed:
        lags.append(forwarder.stats.lag)
        time.sleep(0.05)
    done = time.time()
    forwarder.close()
    out.put((name, t0, done, store.committed, forwarder.stats.forwarded, store.stats.dropped, lags))


def forwarding(url: str, stations: int, rate: int, seconds: float, backlog: bool = False) -> None:
    out: mp.Queue = mp.Queue()
    with tempfile.TemporaryDirectory() as folder:
        procs = [mp.Process(target=station, args=(f"{'b' if backlog else 's'}{k}", folder, url, rate,
                                                   seconds, backlog, out))
                 for k in range(stations)]
        for p in procs:
            p.start()
        results = [out.get() for _ in procs]
        for p in procs:
            p.join()
    start = min(r[1] for r in results)
    end = max(r[2] for r in results)
    sent = sum(r[4] for r in results)
    written = sum(r[3] for r in results)
    if backlog:
        print(f"plant archive: {stations} stations each forwarding a backlog of {rate * seconds:,.0f} "
              f"records at once: {sent:,} of {written:,} in {end - start:.1f} s = "
              f"{sent / (end - start):,.0f} records/s in total  target >= 100,000")
        return
    lags = sorted(lag for r in results for lag in r[6])
    p99 = lags[min(len(lags) - 1, int(0.99 * len(lags)))]
    print(f"plant archive: {stations} stations x {rate:,} records/s for {seconds:.0f} s (offered "
          f"{stations * rate:,}/s): {sent:,} of {written:,} records forwarded "
          f"({sum(r[5] for r in results)} dropped) in {end - start:.1f} s = "
          f"{sent / (end - start):,.0f} records/s")
    print(f"plant archive: forwarding lag p99 {p99:.2f} s, max {lags[-1]:.2f} s")


def yardstick(url: str, n: int) -> None:
    """Raw binary COPY of pre-built rows into the same table and indexes, one process."""
    n = min(n, 500_000)
    now = int(time.time() * 1000)
    day = dt.date.today()
    rows = [("raw", day, i, now + i, "data", 1 + i % 4, 1, f"0{0o4100 + i % 40:o}", None, float(i), None)
            for i in range(1, n + 1)]
    with pg.connect(url) as con:
        tz = pg.plant_zone(con)
        with con.transaction():
            pg.ensure_partitions(con, {pg.plant_day(now, tz), pg.plant_day(now + n, tz)}, tz)
        t0 = time.perf_counter()
        for k in range(0, n, 20_000):
            with con.transaction():
                pg.copy_rows(con, rows[k:k + 20_000])
        rate = n / (time.perf_counter() - t0)
    print(f"plant archive: yardstick, raw binary COPY into the same schema, one process: "
          f"{rate:,.0f} records/s")


def big_day(url: str, n: int) -> None:
    t0 = time.perf_counter()
    with pg.connect(url) as con:
        tz = pg.ensure_schema(con)
        start = dt.datetime(DAY.year, DAY.month, DAY.day, tzinfo=tz).timestamp()
        step = 80_000_000 / n  # ms, all within the day
        with con.transaction():
            pg.ensure_partitions(con, {DAY}, tz)
            con.execute(
                "INSERT INTO records SELECT 'big', %s, i, %s + (i * %s)::bigint, "
                "CASE WHEN i %% 10 = 9 THEN 'message' ELSE 'data' END, "
                "CASE WHEN i %% 10 = 9 THEN (i / 10) %% 8 WHEN i %% 2 = 0 THEN 1 "
                "     ELSE 2 + (i %% 19) %% 4 END, "
                "CASE WHEN i %% 10 = 9 THEN CASE WHEN (i / 10) %% 4 = 0 THEN 2 ELSE (i / 10) %% 2 END "
                "     WHEN i %% 2 = 0 THEN 1 ELSE (i %% 19) %% 5 END, "
                "CASE WHEN i %% 10 = 9 THEN NULL WHEN i %% 2 = 0 THEN '04010' "
                "     ELSE '0' || to_char(2112 + 2 * (i %% 19), 'FM9999') END, "
                "CASE WHEN i %% 10 = 9 THEN 1 + (i / 10) %% 100 END, "
                "CASE WHEN i %% 10 = 9 THEN NULL ELSE (i %% 4096)::float8 END, "
                "CASE WHEN i %% 10 = 9 THEN CASE WHEN (i / 10) %% 4 = 0 THEN 'Авария насоса ' "
                "     ELSE 'Насос ' END || (1 + (i / 10) %% 100) END "
                "FROM generate_series(1, %s) AS i",
                (DAY, round(start * 1000), step, n))
            con.execute("INSERT INTO meta VALUES ('big', 'schema_version', '1') ON CONFLICT DO NOTHING")
        con.execute("ANALYZE records")
    print(f"plant archive: a day of {n:,} records of station 'big' made in {time.perf_counter() - t0:.0f} s")
    cases = {
        "alarms of one station (kind message, type >= 2)": Filter(kinds={"message"}, min_type=2,
                                                                   stations={"big"}),
        "one source of one station": Filter(source="04010", stations={"big"}),
        "text contains 'авария', one station": Filter(text="авария", stations={"big"}),
    }
    for label, flt in cases.items():
        times, rows = [], 0
        for _ in range(OPENS):
            t0 = time.perf_counter()
            with Archive(url) as archive:
                rows = len(archive.records(DAY, flt, limit=200))
            times.append(time.perf_counter() - t0)
        print(f"plant archive: first page, open + {label}, {n:,}-record day: "
              f"{statistics.median(times) * 1000:.1f} ms ({rows} rows)  target < 200 ms")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stations", type=int, default=8)
    parser.add_argument("--rate", type=int, default=10_000, help="records/s per station")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--day-records", type=int, default=10_000_000)
    parser.add_argument("--url", help="an existing plant archive database (default: a throwaway cluster)")
    args = parser.parse_args()
    cluster = None
    url = args.url
    if url is None:
        from tests.pgcluster import PgCluster

        cluster = PgCluster(durable=True)
        cluster.start()
        url = cluster.url
    try:
        with pg.connect(url) as con:
            pg.ensure_schema(con)
        forwarding(url, args.stations, args.rate, args.seconds)
        forwarding(url, args.stations, args.rate, args.seconds, backlog=True)
        yardstick(url, args.stations * args.rate)
        big_day(url, args.day_records)
    finally:
        if cluster is not None:
            cluster.remove()


if __name__ == "__main__":
    main()
