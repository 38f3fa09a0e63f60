"""The plant archive on PostgreSQL: the SQLite layout of every station in one partitioned table.

`records` is partitioned by range of `ts`, one partition per local day named DD_MM_YYYY like the
SQLite day tables; the day is cut in the plant's zone, whose IANA key the first writer stores in
`meta` (station ''), so stations in several zones share the partitions. Each row keeps its
station's name, the station's day table (`day`) and its id there: the unique key (station, day,
id) of each partition makes a replayed batch fail instead of doubling rows. `forwarded` holds the
last id copied per station and day, written in the same transaction as the rows, so a batch and
its position are committed together or not at all.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterable, Sequence

import psycopg

from registrar.schema import (
    SCHEMA_VERSION,
    day_bounds_in,
    local_zone_key,
    parse_table_name,
    table_name,
    zone,
)

PLANT = ""  # the `station` of the plant-wide meta rows
COPY_COLUMNS = ("station", "day", "id", "ts", "kind", "grp", "type", "source", "number", "value", "text")
COPY_TYPES = ("text", "date", "int8", "int8", "text", "int8", "int8", "text", "int8", "float8", "text")
LOCK_PARTITIONS = 7_165_001  # advisory lock key: one writer at a time creates or drops partitions

SCHEMA_SQL = (
    """CREATE TABLE IF NOT EXISTS records (
        station text NOT NULL, day date NOT NULL, id bigint NOT NULL,
        ts bigint NOT NULL, kind text NOT NULL, grp bigint, type bigint, source text,
        number bigint, value double precision, text text
    ) PARTITION BY RANGE (ts)""",
    "CREATE INDEX IF NOT EXISTS records_station_ts ON records (station, ts)",
    "CREATE INDEX IF NOT EXISTS records_key ON records (station, kind, grp, type, source, ts)",
    """CREATE TABLE IF NOT EXISTS meta (station text NOT NULL, key text NOT NULL, value text,
        PRIMARY KEY (station, key))""",
    """CREATE TABLE IF NOT EXISTS messages (station text NOT NULL, number bigint NOT NULL,
        grp bigint, type bigint, text text, PRIMARY KEY (station, number))""",
    """CREATE TABLE IF NOT EXISTS series (station text NOT NULL, day text NOT NULL, kind text NOT NULL,
        grp bigint, type bigint, source text,
        UNIQUE NULLS NOT DISTINCT (station, day, kind, grp, type, source))""",
    """CREATE TABLE IF NOT EXISTS forwarded (station text NOT NULL, day date NOT NULL,
        last_id bigint NOT NULL, PRIMARY KEY (station, day))""",
)


def connect(url: str, *, read_only: bool = False, timeout: float = 5.0) -> psycopg.Connection:
    """Autocommit: every write is inside an explicit `con.transaction()`."""
    options = "-c default_transaction_read_only=on" if read_only else ""
    return psycopg.connect(url, connect_timeout=max(1, round(timeout)), options=options,
                           autocommit=True, application_name="netplc-station")


def ensure_schema(con: psycopg.Connection) -> dt.tzinfo | None:
    """Create the tables once (under the lock, so two stations starting together agree) and
    return the plant's zone, set by the first writer to its own."""
    with con.transaction():
        con.execute("SELECT pg_advisory_xact_lock(%s)", (LOCK_PARTITIONS,))
        for sql in SCHEMA_SQL:
            con.execute(sql)
        con.execute("INSERT INTO meta VALUES (%s, 'schema_version', %s), (%s, 'timezone_key', %s), "
                    "(%s, 'day_partitions', 'one per local day of the plant zone, named DD_MM_YYYY') "
                    "ON CONFLICT DO NOTHING",
                    (PLANT, SCHEMA_VERSION, PLANT, local_zone_key(), PLANT))
    return plant_zone(con)


def plant_zone(con: psycopg.Connection) -> dt.tzinfo | None:
    row = con.execute("SELECT value FROM meta WHERE station = %s AND key = 'timezone_key'",
                      (PLANT,)).fetchone()
    return zone(row[0]) if row else None


def partitions(con: psycopg.Connection) -> dict[dt.date, str]:
    rows = con.execute("SELECT c.relname FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid "
                       "WHERE i.inhparent = 'records'::regclass").fetchall()
    return {d: name for (name,) in rows if (d := parse_table_name(name)) is not None}


def ensure_partitions(con: psycopg.Connection, days: Iterable[dt.date], tz: dt.tzinfo | None) -> None:
    """Create the partitions of `days` (plant-zone days) that are missing, inside the caller's
    transaction; the advisory lock keeps two stations from creating the same one."""
    missing = set(days)
    if not missing:
        return
    con.execute("SELECT pg_advisory_xact_lock(%s)", (LOCK_PARTITIONS,))
    missing -= set(partitions(con))
    for day in sorted(missing):
        start, end = day_bounds_in(day, tz)
        name = table_name(day)
        con.execute(f'CREATE TABLE "{name}" PARTITION OF records FOR VALUES FROM '
                    f"({round(start * 1000)}) TO ({round(end * 1000)})")
        con.execute(f'CREATE UNIQUE INDEX "{name}_local" ON "{name}" (station, day, id)')


def plant_day(ms: int, tz: dt.tzinfo | None) -> dt.date:
    return dt.datetime.fromtimestamp(ms / 1000, tz).date()


def drop_days_before(con: psycopg.Connection, oldest: dt.date) -> list[str]:
    """Detach and drop the partitions of days before `oldest`; their names."""
    with con.transaction():
        con.execute("SELECT pg_advisory_xact_lock(%s)", (LOCK_PARTITIONS,))
        old = sorted((d, n) for d, n in partitions(con).items() if d < oldest)
        for _day, name in old:
            con.execute(f'ALTER TABLE records DETACH PARTITION "{name}"')
            con.execute(f'DROP TABLE "{name}"')
            con.execute("DELETE FROM series WHERE day = %s", (name,))
        con.execute("DELETE FROM forwarded WHERE day < %s", (oldest,))
    return [n for _d, n in old]


def copy_rows(con: psycopg.Connection, rows: Sequence[tuple]) -> None:
    """Binary COPY of rows in COPY_COLUMNS order into `records` (the caller's transaction)."""
    with con.cursor() as cur, cur.copy(
            f"COPY records ({', '.join(COPY_COLUMNS)}) FROM STDIN (FORMAT BINARY)") as copy:
        copy.set_types(COPY_TYPES)
        write = copy.write_row
        for row in rows:
            write(row)


def insert_rows_once(con: psycopg.Connection, rows: Sequence[tuple]) -> None:
    """The rows not there yet (the slow path, after a replayed batch hit the unique key)."""
    with con.cursor() as cur:
        cur.executemany(f"INSERT INTO records ({', '.join(COPY_COLUMNS)}) "
                        f"VALUES ({', '.join(['%s'] * len(COPY_COLUMNS))}) ON CONFLICT DO NOTHING", rows)
