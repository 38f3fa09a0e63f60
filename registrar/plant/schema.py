"""The plant archive on PostgreSQL: the SQLite layout of every station in one partitioned table.

`records` is partitioned by range of `ts`, one partition per local day named DD_MM_YYYY like the
SQLite day tables; the day is cut in the plant's zone, whose IANA key the first writer stores in
`meta` (station ''), so stations in several zones share the partitions. Each row keeps its
station's name, the station's day table (`day`) and its id there: the unique key (station, day,
id) of each partition makes a replayed batch fail instead of doubling rows. `forwarded` holds the
last id copied per station and day, written in the same transaction as the rows, so a batch and
its position are committed together or not at all.

The two stations of a hot-standby pair forward under their one name, each its own archive: a
record's id there is its local id plus its letter's base (PAIR_ID_BASE: A from 2^40, B from 2^41),
so the two never collide and each keeps its own order, and each letter's position is a row of
`forwarded_pair`. A record both stations may hold (kept by the standby for a takeover) is keyed by
its pid instead (app/station/pair.py: its ms << 12, far above the letters' ids), the same in
both. Queries order by time, so the pair's records read as one history.

`tags` keeps every version of each station's tags (its tags.csv as the station's archive holds
it), each valid from the change that made it to the next one, and the view `tag_values` gives
every data record of a one-word tag by the version of its time: time, station, tag, the physical
value, unit and quality, the columns Grafana's PostgreSQL data source plots as they are.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
from collections.abc import Iterable, Sequence

import psycopg

from registrar.schema import (
    GAP_SQL,
    ONE_WORD_TYPES,
    SCHEMA_VERSION,
    TAG_FIELDS,
    day_bounds_in,
    local_zone_key,
    parse_table_name,
    physical_sql,
    table_name,
    zone,
)

PLANT = ""  # the `station` of the plant-wide meta rows
PAIR_ID_BASE = {"A": 1 << 40, "B": 2 << 40}  # a pair's records: local id + its letter's base
COPY_COLUMNS = ("station", "day", "id", "ts", "kind", "grp", "type", "source", "number", "value", "text")
COPY_TYPES = ("text", "date", "int8", "int8", "text", "int8", "int8", "text", "int8", "float8", "text")
LOCK_PARTITIONS = 7_165_001  # advisory lock key: one writer at a time creates or drops partitions
LOCK_TAGS = 7_165_002  # with the station's hash: one writer at a time changes a station's tag versions
TAG_COLUMNS = (*TAG_FIELDS, "source")  # a tag as the forwarder reads it from the station's archive
EPOCH = dt.datetime(1970, 1, 1, tzinfo=dt.UTC)

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
    """CREATE TABLE IF NOT EXISTS forwarded_pair (station text NOT NULL, letter text NOT NULL,
        day date NOT NULL, last_id bigint NOT NULL, PRIMARY KEY (station, letter, day))""",
    # A station's tags, one row per tag and version: a version converts the records from valid_from
    # (the first '-infinity') to valid_to (the current 'infinity'); `since` is when the station took
    # it up (its archive's `tags_since`; NULL: not known); `source` is the key of its data records.
    """CREATE TABLE IF NOT EXISTS tags (station text NOT NULL, version integer NOT NULL,
        valid_from timestamptz NOT NULL, valid_to timestamptz NOT NULL, since timestamptz,
        hash text NOT NULL,
        name text NOT NULL, address bigint NOT NULL, type text NOT NULL, unit text,
        app_min double precision, app_max double precision, phy_min double precision,
        phy_max double precision, decimals integer, description text, source text NOT NULL,
        PRIMARY KEY (station, version, name))""",
    "CREATE INDEX IF NOT EXISTS tags_source ON tags (station, source, valid_from)",
)

# Every data record of a one-word tag in physical units, by the tag version of its time, as
# the station converts it (registrar/schema.py physical_sql); no value where the station's
# readers break a series (the record of a value that was held: GAP_SQL). `ts` is there so a
# time filter on it reaches the day partitions (one on `time`, an expression, reads them all).
# Made once, by whoever finds it missing: replacing it needs its owner, and stations may log in
# as different roles.
TAG_VALUES_SQL = f"""CREATE VIEW tag_values AS
    SELECT r.time, r.station, t.name AS tag, t.name AS metric,
        CASE WHEN r.gap THEN NULL ELSE {physical_sql("r.value", "t")} END AS value,
        t.unit, coalesce(r.text, 'good') AS quality, r.ts, r.source, r.value AS raw, t.version
    FROM (SELECT station, ts, source, value, text, {GAP_SQL} AS gap,
            timestamptz 'epoch' + ts * interval '1 millisecond' AS time
        FROM records WHERE kind = 'data') r
    JOIN tags t ON t.station = r.station AND t.source = r.source
        AND r.time >= t.valid_from AND r.time < t.valid_to
    WHERE t.type IN ({", ".join(f"'{k}'" for k in ONE_WORD_TYPES)})"""


def connect(url: str, *, read_only: bool = False, timeout: float = 5.0, options: str = "",
            **params: object) -> psycopg.Connection:
    """Autocommit: every write is inside an explicit `con.transaction()`. `options`: the
    session's server settings (`-c name=value`), `params`: more libpq connection parameters."""
    if read_only:
        options = f"{options} -c default_transaction_read_only=on".strip()
    return psycopg.connect(url, connect_timeout=max(1, round(timeout)), options=options,
                           autocommit=True, application_name="netplc-station", **params)


def ensure_schema(con: psycopg.Connection) -> dt.tzinfo | None:
    """Create the tables once (under the lock, so two stations starting together agree) and
    return the plant's zone, set by the first writer to its own."""
    with con.transaction():
        con.execute("SELECT pg_advisory_xact_lock(%s)", (LOCK_PARTITIONS,))
        for sql in SCHEMA_SQL:
            con.execute(sql)
        if con.execute("SELECT to_regclass('tag_values')").fetchone()[0] is None:
            con.execute(TAG_VALUES_SQL)
        con.execute("INSERT INTO meta VALUES (%s, 'timezone_key', %s), "
                    "(%s, 'day_partitions', 'one per local day of the plant zone, named DD_MM_YYYY') "
                    "ON CONFLICT DO NOTHING", (PLANT, local_zone_key(), PLANT))
        con.execute("INSERT INTO meta VALUES (%s, 'schema_version', %s) ON CONFLICT (station, key) "
                    "DO UPDATE SET value = excluded.value "
                    "WHERE lpad(meta.value, 9, '0') < lpad(excluded.value, 9, '0')",  # never back
                    (PLANT, SCHEMA_VERSION))
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
        con.execute("DELETE FROM forwarded_pair WHERE day < %s", (oldest,))
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


def publish_tags(con: psycopg.Connection, station: str, rows: Sequence[tuple], since_ms: int | None) -> None:
    """Make `rows` (TAG_COLUMNS) the station's tags from `since_ms` on (None: not known), inside the
    caller's transaction. The first version is read for records of any time; a set equal to the
    version in force then changes nothing (a restart, a migrate after the forwarder, twice); another
    one splits that version there, so the records before keep the tags of their time, or, when it
    comes from before the version in force was taken up (an older copy of the archive migrated
    late), takes the time before that. Where a version already starts at that moment, it stays."""
    if not rows:
        return
    digest = tags_hash(rows)
    since = None if since_ms is None else EPOCH + dt.timedelta(milliseconds=since_ms)
    at = {"station": station, "at": "-infinity" if since is None else since}
    con.execute("SELECT pg_advisory_xact_lock(%s, hashtext(%s))", (LOCK_TAGS, station))
    held = con.execute(
        "SELECT version, hash = %(hash)s OR valid_from = %(at)s::timestamptz, %(at)s::timestamptz < since, "
        "valid_from::text, valid_to::text, since::text FROM tags WHERE station = %(station)s "
        "AND valid_from <= %(at)s::timestamptz AND %(at)s::timestamptz < valid_to LIMIT 1",
        {**at, "hash": digest}).fetchone()
    last = con.execute("SELECT coalesce(max(version), 0) FROM tags WHERE station = %s",
                       (station,)).fetchone()[0]
    valid_from, valid_to = "-infinity", "infinity"  # the station's first tags
    if held is not None:
        old, known, earlier, old_from, old_to, old_since = held
        if known:
            return
        if earlier:  # it held before the version in force was taken up
            valid_from, valid_to = old_from, old_since
            con.execute("UPDATE tags SET valid_from = since WHERE station = %s AND version = %s",
                        (station, old))
        else:
            valid_from, valid_to = at["at"], old_to
            con.execute("UPDATE tags SET valid_to = %(at)s::timestamptz WHERE station = %(station)s "
                        "AND version = %(old)s", {**at, "old": old})
    elif last:  # a gap in the versions (edited by hand): this set fills it up to the next one
        valid_from = at["at"]
        valid_to = con.execute("SELECT coalesce(min(valid_from), 'infinity')::text FROM tags "
                               "WHERE station = %s AND valid_from > %s::timestamptz",
                               (station, valid_from)).fetchone()[0]
    columns = ("station", "version", "valid_from", "valid_to", "since", "hash", *TAG_COLUMNS)
    with con.cursor() as cur:
        cur.executemany(f"INSERT INTO tags ({', '.join(columns)}) VALUES (%s, %s, %s::timestamptz, "
                        f"%s::timestamptz, {', '.join(['%s'] * (len(columns) - 4))})",
                        [(station, last + 1, valid_from, valid_to, since, digest, *row) for row in rows])


def tags_hash(rows: Sequence[tuple]) -> str:
    """What tells two tag sets apart: the SHA-256 of their rows in name order."""
    text = json.dumps(sorted(rows, key=lambda r: r[0]), ensure_ascii=False, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()
