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
from dataclasses import dataclass, replace
from pathlib import Path
from typing import NamedTuple
from urllib.parse import quote

import numpy as np

from netplc.tags.tag import Tag
from registrar.schema import (
    COLUMNS,
    DAY_GLOB,
    key_index,
    parse_table_name,
    quoted,
    table_name,
    tags_by_source,
    text_index,
)

EXPORT_CHUNK = 10_000
PROBE_ROWS = 20_000  # newest rows tried first for a page (a couple of milliseconds)
INDEX_ROWS = 50_000  # up to this many index matches are fetched and sorted rather than scanned
SCAN_ABOVE = 0.125  # a series holding more than this share of its day is read by a table scan


@dataclass(frozen=True)
class Filter:
    kinds: set[str] | frozenset[str] | None = None
    grp: int | None = None
    type: int | None = None
    min_type: int | None = None  # e.g. 2: alarms and worse
    source: str | None = None
    text: str | None = None  # contains
    since: float | None = None  # seconds since the epoch, inclusive
    until: float | None = None  # seconds since the epoch, exclusive


@dataclass(frozen=True, slots=True)
class Row:
    id: int
    ts: float  # seconds since the epoch
    kind: str
    grp: int | None
    type: int | None
    source: str | None
    number: int | None
    value: float | None
    text: str | None

    @property
    def time(self) -> dt.datetime:
        """Local time of the record."""
        return dt.datetime.fromtimestamp(self.ts)


class SeriesKey(NamedTuple):
    kind: str
    grp: int | None
    type: int | None
    source: str | None


_SELECT = "SELECT " + ", ".join(COLUMNS)


class Archive:
    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise FileNotFoundError(f"{self.path}: no such archive")
        self._con = self._connect()

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

    def __enter__(self) -> Archive:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

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
            return tags_by_source(self._con.execute("SELECT * FROM tags").fetchall())
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
        where, args = _where(flt)
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
            return [_row(r) for r in rows]
        # 2. Rare matches of indexed keys: fetch them through the index and sort them.
        keyed = self._keyed(day, flt) if self._has_index(key_index(table_name(day))) else None
        if keyed is not None:
            where, args = _where(keyed)
            index = f'"{key_index(table_name(day))}"'
            return [_row(r) for r in self._con.execute(
                f"{_SELECT} FROM {table} INDEXED BY {index}{where} {page}", [*args, limit, offset])]
        # 3. Everything else: one pass in id order, stopping at the page; a text search passes
        #    over the rows that have a text only.
        source = "NOT INDEXED"
        if flt.text and self._has_index(text_index(table_name(day))):
            source = f'INDEXED BY "{text_index(table_name(day))}"'
        return [_row(r) for r in self._con.execute(
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
        where, args = _where(prefix)
        index = f'"{key_index(table_name(day))}"'
        n = self._con.execute(
            f"SELECT count(*) FROM (SELECT 1 FROM {table} INDEXED BY {index}{where} LIMIT {INDEX_ROWS + 1})",
            args).fetchone()[0]
        return flt if n <= INDEX_ROWS else None

    def count(self, day: dt.date, flt: Filter | None = None) -> int:
        if not self._has(day):
            return 0
        where, args = _where(flt or Filter())
        return self._con.execute(f"SELECT count(*) FROM {quoted(day)}{where}", args).fetchone()[0]

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
            where, args = _where(flt or Filter())
            cur = self._con.execute(f"{_SELECT} FROM {quoted(day)} NOT INDEXED{where} ORDER BY id", args)
            try:
                while chunk := cur.fetchmany(EXPORT_CHUNK):
                    for r in chunk:
                        local = dt.datetime.fromtimestamp(r[1] / 1000).isoformat(timespec="milliseconds")
                        tag = tags.get(r[at]) if r[2] == "data" and r[7] is not None else None
                        phy = [] if tag is None else [
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
        # A series holding a good part of the day is read faster by a scan than by index lookups.
        total = self._con.execute(f"SELECT max(id) FROM {table}").fetchone()[0] or 0
        many = round(SCAN_ABOVE * total)
        n = self._con.execute(f"SELECT count(*) FROM (SELECT 1 FROM {table}{where} LIMIT {many + 1})",
                              args).fetchone()[0]
        if n == 0:
            return empty
        hint = " NOT INDEXED" if n > many else ""
        cur = self._con.execute(
            f"SELECT ts, value FROM {table}{hint}{where} AND value IS NOT NULL ORDER BY id", args)
        data = np.fromiter(cur, dtype=[("ts", "i8"), ("value", "f8")])
        ts = data["ts"]
        if len(ts) > 1 and np.any(ts[1:] < ts[:-1]):  # the wall clock was set back
            data = data[np.argsort(ts, kind="stable")]
        ts, values = data["ts"] / 1000.0, data["value"]
        if len(ts) <= points:
            return ts, values
        return _min_max(ts, values, max(1, points // 2))

    # --- helpers -------------------------------------------------------------------------------

    def _has_index(self, name: str) -> bool:
        return self._con.execute("SELECT 1 FROM sqlite_master WHERE type = 'index' AND name = ?",
                                 (name,)).fetchone() is not None

    def _has(self, day: dt.date) -> bool:
        return self._con.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?",
                                 (table_name(day),)).fetchone() is not None


def _open_ro(uri: str) -> sqlite3.Connection:
    con = sqlite3.connect(uri, uri=True, isolation_level=None, check_same_thread=False)
    try:
        con.execute("SELECT count(*) FROM sqlite_master").fetchone()
        con.execute("PRAGMA query_only=1")
    except sqlite3.Error:
        con.close()
        raise
    return con


def _row(r: tuple) -> Row:
    return Row(r[0], r[1] / 1000.0, *r[2:])


def _where(flt: Filter) -> tuple[str, list[object]]:
    conds: list[str] = []
    args: list[object] = []
    if flt.kinds is not None:
        kinds = sorted(flt.kinds)
        conds.append(f"kind IN ({', '.join('?' * len(kinds))})" if kinds else "0")
        args.extend(kinds)
    for col, val in (("grp", flt.grp), ("type", flt.type), ("source", flt.source)):
        if val is not None:
            conds.append(f"{col} = ?")
            args.append(val)
    if flt.min_type is not None:
        conds.append("type >= ?")
        args.append(flt.min_type)
    if flt.since is not None:
        conds.append("ts >= ?")
        args.append(round(flt.since * 1000))
    if flt.until is not None:
        conds.append("ts < ?")
        args.append(round(flt.until * 1000))
    if flt.text:
        # SQLite folds case for ASCII only; the usual spellings of a Cyrillic word are tried too.
        variants = sorted({flt.text, flt.text.lower(), flt.text.upper(), flt.text.capitalize()})
        likes = " OR ".join("text LIKE ? ESCAPE '\\'" for _ in variants)
        conds.append(f"text IS NOT NULL AND ({likes})")
        args.extend(f"%{_escape_like(v)}%" for v in variants)
    return (" WHERE " + " AND ".join(conds)) if conds else "", args


def _and(where: str, cond: str) -> str:
    return f"{where} AND {cond}" if where else f" WHERE {cond}"


def _escape_like(text: str) -> str:
    return text.replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_")


def _min_max(ts: np.ndarray, values: np.ndarray, buckets: int) -> tuple[np.ndarray, np.ndarray]:
    """Per equal-time bucket, the minimum and the maximum in the order they occurred."""
    edges = np.linspace(ts[0], ts[-1], buckets + 1)
    idx = np.clip(np.searchsorted(edges, ts, side="right") - 1, 0, buckets - 1)
    starts = np.flatnonzero(np.r_[True, idx[1:] != idx[:-1]])
    lo = _arg_reduce(values, starts, np.minimum)
    hi = _arg_reduce(values, starts, np.maximum)
    keep = np.unique(np.concatenate([lo, hi]))
    return ts[keep], values[keep]


def _arg_reduce(values: np.ndarray, starts: np.ndarray, op: np.ufunc) -> np.ndarray:
    """Index of the first element equal to each segment's reduction (segments begin at `starts`)."""
    best = op.reduceat(values, starts)
    seg = np.repeat(np.arange(len(starts)), np.diff(np.r_[starts, len(values)]))
    hits = np.flatnonzero(values == best[seg])
    first = np.r_[True, seg[hits][1:] != seg[hits][:-1]]
    return hits[first]
