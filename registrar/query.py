"""The read side of the archive: the operator's journal, the offline viewer, CSV export.

The file is opened read-only, and in WAL mode a reader sees the last committed state without ever
blocking the writer. Every statement is fetched completely before returning, so no read
transaction stays open to hold back the writer's checkpoints. A copy on read-only media, where
SQLite cannot make its -shm file, is opened as immutable.

Pages are in id order (newest first by default) and are found in three steps: the newest 20,000
rows are filtered first (the first page of a common filter is there); a filter naming kinds or a
group whose matches are few takes them from the key index and sorts them (the journal's messages
among a day of NSTORE data); anything else passes over the day once in id order, stopping at the
page (a text search over the text index: rows with a text only). Series use the key index too,
whose rows for one key come out in id order.
"""

from __future__ import annotations

import csv
import datetime as dt
import sqlite3
from dataclasses import replace
from pathlib import Path
from urllib.parse import quote

from app.scada.tag import Tag
from netplc.lazy import lazy
from registrar.plant.url import is_url
from registrar.reading import (
    EXPORT_CHUNK,
    ArchiveReader,
    ArchiveSource,
    Filter,
    Row,
    SeriesKey,
    thinned,
    where_clause,
)
from registrar.schema import (
    COLUMNS,
    DAY_GLOB,
    GAP_SQL,
    TAG_ROWS_SQL,
    fts_table,
    gap_index,
    key_index,
    minutes_table,
    parse_table_name,
    quoted,
    table_name,
    tags_by_source,
    text_index,
    zone,
)

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it

PROBE_ROWS = 20_000  # newest rows tried first for a page (a couple of milliseconds)
INDEX_ROWS = 50_000  # up to this many index matches are fetched and sorted rather than scanned
SCAN_ABOVE = 0.125  # a series holding more than this share of its day is read by a table scan
SUMMARY_ABOVE = 100_000  # a series of more records is read from the per-minute summary


_SELECT = "SELECT " + ", ".join(COLUMNS)


class Archive(ArchiveReader):
    """A station's SQLite archive, or the plant archive when given a postgresql:// URL (the same
    methods, see registrar/plant/query.py), or what an `ArchiveSource` opens (a station's archive
    at a remote console)."""

    def __new__(cls, target: str | Path | ArchiveSource) -> ArchiveReader:  # type: ignore[misc]
        if cls is Archive and not isinstance(target, str | Path):
            return target.open()
        if cls is Archive and is_url(target):
            from registrar.plant.query import PgArchive  # psycopg only where a plant archive is read

            return PgArchive(target)  # not an Archive, so __init__ below is not run on it
        return super().__new__(cls)

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise FileNotFoundError(f"{self.path}: no such archive")
        self._con = self._connect()
        self.tz = self._zone()

    def _zone(self) -> dt.tzinfo | None:
        """The writer's zone, by the IANA key it stored (older archives: this machine's)."""
        try:
            return zone(self.meta().get("timezone_key", ""))
        except sqlite3.Error:
            return None

    def _connect(self) -> sqlite3.Connection:
        uri = f"file:{quote(str(self.path.resolve()))}?mode=ro"
        try:
            return _open_ro(uri)
        except sqlite3.Error:
            pass  # e.g. a WAL archive on read-only media, where no -shm file can be made
        try:
            # Nobody can be writing there: read the file as it is (a live WAL would be ignored).
            return _open_ro(uri + "&immutable=1")
        except sqlite3.Error as e:
            raise type(e)(f"{self.path}: cannot open the archive: {e}") from e

    def close(self) -> None:
        self._con.close()

    # --- days and catalogues -------------------------------------------------------------------

    def days(self) -> list[dt.date]:
        names = self._con.execute(
            "SELECT name FROM sqlite_master WHERE type = 'table' AND name GLOB ?", (DAY_GLOB,)).fetchall()
        return sorted((d for (n,) in names if (d := parse_table_name(n)) is not None), reverse=True)

    def meta(self) -> dict[str, str]:
        return dict(self._con.execute("SELECT key, value FROM meta").fetchall())

    def message_texts(self) -> dict[int, str]:
        """The catalog as it was copied into the archive."""
        return dict(self._con.execute("SELECT number, text FROM messages").fetchall())

    def tags(self) -> dict[str, Tag]:
        """The station's one-word tags as copied into the archive, by the `source` of the data
        records NSTORE writes of them ({} for an archive written without tags)."""
        try:
            return tags_by_source(self._con.execute(TAG_ROWS_SQL).fetchall())
        except sqlite3.OperationalError:  # no tags table: an archive of an older station
            return {}

    def series_keys(self, day: dt.date) -> list[SeriesKey]:
        rows = self._con.execute(
            "SELECT kind, grp, type, source FROM series WHERE day = ? ORDER BY kind, grp, type, source",
            (table_name(day),)).fetchall()
        return [SeriesKey(*r) for r in rows]

    # --- records -------------------------------------------------------------------------------

    def records(self, day: dt.date, flt: Filter | None = None, offset: int = 0, limit: int = 200,
                newest_first: bool = True) -> list[Row]:
        """A page of the day in id order; see the module docstring for how it is found fast."""
        if limit <= 0 or not self._has(day):
            return []
        flt = flt or Filter()
        table = quoted(day)
        order = "DESC" if newest_first else "ASC"
        page = f"ORDER BY id {order} LIMIT ? OFFSET ?"
        where, args = where_clause(flt)
        # 1. The newest (oldest) rows only: enough whenever the filter matches commonly.
        hi = self._con.execute(f"SELECT max(id) FROM {table}").fetchone()[0]
        lo = self._con.execute(f"SELECT min(id) FROM {table}").fetchone()[0]
        if hi is None:
            return []
        if newest_first:
            window, whole = f"id > {hi - PROBE_ROWS}", lo > hi - PROBE_ROWS
        else:
            window, whole = f"id < {lo + PROBE_ROWS}", hi < lo + PROBE_ROWS
        rows = self._con.execute(f"{_SELECT} FROM {table} NOT INDEXED {_and(where, window)} {page}",
                                 [*args, limit, offset]).fetchall()
        if len(rows) == limit or whole:
            return [self._row(r) for r in rows]
        # 2. Rare matches of indexed keys: fetch them through the index and sort them.
        keyed = self._keyed(day, flt) if self._has_index(key_index(table_name(day))) else None
        if keyed is not None:
            where, args = where_clause(keyed)
            index = f'"{key_index(table_name(day))}"'
            return [self._row(r) for r in self._con.execute(
                f"{_SELECT} FROM {table} INDEXED BY {index}{where} {page}", [*args, limit, offset])]
        # 3. A text search: the rows whose text holds every trigram of the text, by the day's
        #    trigram index (the LIKE filter then decides, as on every other path).
        candidates = self._text_candidates(day, flt)
        if candidates:
            where, args = where_clause(flt)
            return [self._row(r) for r in self._con.execute(
                f"{_SELECT} FROM {table}{_and(where, candidates[0])} {page}",
                [*args, candidates[1], limit, offset])]
        # 4. Everything else: one pass in id order, stopping at the page; a text search of a day
        #    without the trigram index passes over the rows that have a text only.
        source = "NOT INDEXED"
        if flt.text and self._has_index(text_index(table_name(day))):
            source = f'INDEXED BY "{text_index(table_name(day))}"'
        return [self._row(r) for r in self._con.execute(
            f"{_SELECT} FROM {table} {source}{where} {page}", [*args, limit, offset])]

    def _keyed(self, day: dt.date, flt: Filter) -> Filter | None:
        """The filter with its kinds spelt out, if the key index narrows it to few rows."""
        if flt.kinds is None and flt.grp is None:
            return None
        table = quoted(day)
        if flt.kinds is None:
            # Every kind present, by a loose index scan (one index seek per kind).
            kinds = {k for (k,) in self._con.execute(
                f"WITH RECURSIVE k(x) AS (SELECT min(kind) FROM {table} UNION ALL "
                f"SELECT (SELECT min(kind) FROM {table} WHERE kind > x) FROM k WHERE x IS NOT NULL) "
                "SELECT x FROM k WHERE x IS NOT NULL")}
            flt = replace(flt, kinds=kinds)
        prefix = replace(Filter(), kinds=flt.kinds)
        for col in ("grp", "type", "source"):
            if getattr(flt, col) is None:
                break
            prefix = replace(prefix, **{col: getattr(flt, col)})
        where, args = where_clause(prefix)
        index = f'"{key_index(table_name(day))}"'
        n = self._con.execute(
            f"SELECT count(*) FROM (SELECT 1 FROM {table} INDEXED BY {index}{where} LIMIT {INDEX_ROWS + 1})",
            args).fetchone()[0]
        return flt if n <= INDEX_ROWS else None

    def count(self, day: dt.date, flt: Filter | None = None) -> int:
        if not self._has(day):
            return 0
        flt = flt or Filter()
        where, args = where_clause(flt)
        candidates = self._text_candidates(day, flt)
        if candidates:
            where, args = _and(where, candidates[0]), [*args, candidates[1]]
        return self._con.execute(f"SELECT count(*) FROM {quoted(day)}{where}", args).fetchone()[0]

    def _text_candidates(self, day: dt.date, flt: Filter) -> tuple[str, str] | None:
        """The condition and argument limiting a text search to the trigram index's candidates
        (None: no text of 3 or more characters, or a day written before the index)."""
        if (not flt.text or len(flt.text) < 3 or "\x00" in flt.text  # FTS5 queries end at a NUL
                or not self._has_table(fts_table(table_name(day)))):
            return None
        fts = f'"{fts_table(table_name(day))}"'
        return f"id IN (SELECT rowid FROM {fts} WHERE {fts} MATCH ?)", _trigrams(flt.text)

    def export_csv(self, path: str | Path, day: dt.date, flt: Filter | None = None) -> int:
        """Write the selection oldest first; UTF-8 with a BOM so spreadsheets read Cyrillic. A data
        record of a tag's address also names the tag and gives its physical value and unit (the
        raw value stays in `value`)."""
        n = 0
        tags = self.tags()
        at = COLUMNS.index("source")
        with open(path, "w", newline="", encoding="utf-8-sig") as f:
            out = csv.writer(f)
            out.writerow(["id", "time", *COLUMNS[1:], "tag", "physical", "unit"])
            if not self._has(day):
                return 0
            where, args = where_clause(flt or Filter())
            cur = self._con.execute(f"{_SELECT} FROM {quoted(day)} NOT INDEXED{where} ORDER BY id", args)
            try:
                while chunk := cur.fetchmany(EXPORT_CHUNK):
                    for r in chunk:
                        local = self.local_time(r[1] / 1000).isoformat(timespec="milliseconds")
                        tag = tags.get(r[at]) if r[2] == "data" and r[7] is not None else None
                        phy = ["", "", ""] if tag is None else [  # every row the header's fields
                            tag.name, f"{tag.word_value(int(r[7])):.{tag.decimals}f}", tag.unit]
                        out.writerow([r[0], local, *r[1:], *phy])
                    n += len(chunk)
            finally:
                cur.close()
        return n

    # --- series --------------------------------------------------------------------------------

    def series(self, day: dt.date, *, grp: int | None = None, type: int | None = None,
               source: str | None = None, points: int = 1000) -> tuple[np.ndarray, np.ndarray]:
        """Times (s) and values of the day's data records, reduced to about `points` points.

        Above `points` the day is cut into points/2 equal time buckets and each keeps its minimum
        and its maximum at their own times, so peaks survive the reduction.
        """
        empty = (np.empty(0), np.empty(0))
        if not self._has(day):
            return empty
        conds = ["kind = 'data'"]
        args: list[object] = []
        for col, val in (("grp", grp), ("type", type), ("source", source)):
            if val is not None:
                conds.append(f"{col} = ?")
                args.append(val)
        where = " WHERE " + " AND ".join(conds)
        table = quoted(day)
        if grp is not None and type is not None and source is not None:
            summary = self._summary(day, grp, type, source)
            if summary is not None:
                return thinned(*summary, points)
        # A series holding a good part of the day is read faster by a scan than by index lookups.
        total = self._con.execute(f"SELECT max(id) FROM {table}").fetchone()[0] or 0
        many = round(SCAN_ABOVE * total)
        n = self._con.execute(f"SELECT count(*) FROM (SELECT 1 FROM {table}{where} LIMIT {many + 1})",
                              args).fetchone()[0]
        if n == 0:
            return empty
        hint = " NOT INDEXED" if n > many else ""
        cur = self._con.execute(
            f"SELECT ts, coalesce(value, 0), {GAP_SQL} FROM {table}{hint}{where} "
            f"AND (value IS NOT NULL OR {GAP_SQL}) ORDER BY id", args)
        data = np.fromiter(cur, dtype=[("ts", "i8"), ("value", "f8"), ("gap", "?")])
        ts = data["ts"]
        if len(ts) > 1 and np.any(ts[1:] < ts[:-1]):  # the wall clock was set back
            data = data[np.argsort(ts, kind="stable")]
        values = np.where(data["gap"], np.nan, data["value"])
        return thinned(data["ts"] / 1000.0, values, points)

    # --- time windows, for Historical Access (app/publish/history.py) ---------------------------

    def first_at(self, day: dt.date, ts_ms: int) -> int:
        """The smallest id of the day whose record is at or after `ts_ms` (one past its last id
        when none is), found by bisection over the primary key: the writer appends records in
        time order. A wall clock set back breaks that order; `window` still keeps to the times
        asked, but may then miss records written around the change."""
        if not self._has(day):
            return 1
        table = quoted(day)
        # two subqueries: SQLite answers a lone min() or max() of the key from the B-tree's ends,
        # but both in one SELECT by a scan of the table
        lo, hi = self._con.execute(
            f"SELECT (SELECT min(id) FROM {table}), (SELECT max(id) FROM {table})").fetchone()
        if lo is None:
            return 1
        hi += 1
        while lo < hi:
            mid = (lo + hi) // 2
            at, ts = self._con.execute(f"SELECT id, ts FROM {table} WHERE id >= ? ORDER BY id LIMIT 1",
                                       (mid,)).fetchone()
            if ts >= ts_ms:
                hi = mid
            else:
                lo = at + 1
        return lo

    def window(self, day: dt.date, ids: tuple[int, int], *, kinds: tuple[str, ...] = (),
               key: SeriesKey | None = None, times: tuple[int, int] | None = None,
               newest_first: bool = False, limit: int = 1) -> list[Row]:
        """Up to `limit` records of the day with ids[0] <= id < ids[1], of `kinds`, of the series
        `key` (kind, grp, type and source) when given, with times[0] <= ts <= times[1] (ms) when
        given, in id order. A series is read through the key index (its rows come out in id
        order); other records by the primary key alone (their window is bounded by the caller)."""
        if not self._has(day) or ids[0] >= ids[1] or limit <= 0:
            return []
        conds = ["id >= ?", "id < ?"]
        args: list[object] = [*ids]
        if key is not None:
            conds += ["kind = ?", "grp = ?", "type = ?", "source = ?"]
            args += [key.kind, key.grp, key.type, key.source]
            source = ""
        else:
            conds.append(f"kind IN ({', '.join('?' * len(kinds))})")
            args += kinds
            source = " NOT INDEXED"
        if times is not None:
            conds.append("ts BETWEEN ? AND ?")
            args += times
        order = "DESC" if newest_first else "ASC"
        return [self._row(r) for r in self._con.execute(
            f"{_SELECT} FROM {quoted(day)}{source} WHERE {' AND '.join(conds)} ORDER BY id {order} LIMIT ?",
            [*args, limit])]

    # --- helpers -------------------------------------------------------------------------------

    def _row(self, r: tuple) -> Row:
        return Row(r[0], r[1] / 1000.0, *r[2:], tz=self.tz)

    def _summary(self, day: dt.date, grp: int, type: int,
                 source: str) -> tuple[np.ndarray, np.ndarray] | None:
        """The series from the per-minute minima and maxima at their own times, when it is long
        enough for that to pay (None: read the records), with its gaps (NaN) at their times."""
        minutes = minutes_table(table_name(day))
        if not self._has_table(minutes):
            return None
        key = "WHERE grp = ? AND type = ? AND source = ?"
        total = self._con.execute(f'SELECT sum(n) FROM "{minutes}" {key}', (grp, type, source)).fetchone()[0]
        if not total or total <= SUMMARY_ABOVE:
            return None
        cur = self._con.execute(f'SELECT lo_ts, lo, hi_ts, hi FROM "{minutes}" {key} ORDER BY minute',
                                (grp, type, source))
        data = np.fromiter(cur, dtype=[("lo_ts", "i8"), ("lo", "f8"), ("hi_ts", "i8"), ("hi", "f8")])
        ts = np.column_stack([data["lo_ts"], data["hi_ts"]]).ravel()
        values = np.column_stack([data["lo"], data["hi"]]).ravel()
        order = np.argsort(ts, kind="stable")
        ts, values = ts[order], values[order]
        keep = np.r_[True, (ts[1:] != ts[:-1]) | (values[1:] != values[:-1])]  # min and max one record
        gaps = np.empty(0, dtype=np.int64)
        index = gap_index(table_name(day))
        if self._has_index(index):  # a day written without it has no gaps
            gaps = np.fromiter((t for (t,) in self._con.execute(
                f'SELECT ts FROM {quoted(day)} INDEXED BY "{index}" WHERE kind = \'data\' AND grp = ? '
                f"AND type = ? AND source = ? AND {GAP_SQL}", (grp, type, source))), dtype=np.int64)
        ts = np.concatenate((ts[keep], gaps))
        values = np.concatenate((values[keep], np.full(len(gaps), np.nan)))
        order = np.argsort(ts, kind="stable")
        return ts[order] / 1000.0, values[order]

    def _has_table(self, name: str) -> bool:
        return self._con.execute("SELECT 1 FROM sqlite_master WHERE name = ?", (name,)).fetchone() is not None

    def _has_index(self, name: str) -> bool:
        return self._con.execute("SELECT 1 FROM sqlite_master WHERE type = 'index' AND name = ?",
                                 (name,)).fetchone() is not None

    def _has(self, day: dt.date) -> bool:
        return self._con.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?",
                                 (table_name(day),)).fetchone() is not None


def available(target: str | Path | ArchiveSource) -> bool:
    """Whether an archive is there to read now: a file that exists, a plant archive's URL (its
    reads say when it is out of reach), a source that says so."""
    if isinstance(target, str | Path):
        return is_url(target) or Path(target).exists()
    return target.available()


def _open_ro(uri: str) -> sqlite3.Connection:
    con = sqlite3.connect(uri, uri=True, isolation_level=None, check_same_thread=False)
    try:
        con.execute("SELECT count(*) FROM sqlite_master").fetchone()
        con.execute("PRAGMA query_only=1")
    except sqlite3.Error:
        con.close()
        raise
    return con




def _trigrams(text: str) -> str:
    """An FTS5 query for rows holding every trigram of `text` (the index folds case itself)."""
    quoted_ = ('"' + text[i:i + 3].replace('"', '""') + '"' for i in range(len(text) - 2))
    return " AND ".join(dict.fromkeys(quoted_))


def _and(where: str, cond: str) -> str:
    return f"{where} AND {cond}" if where else f" WHERE {cond}"
