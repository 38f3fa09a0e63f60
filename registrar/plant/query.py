"""The read side of the plant archive: registrar.query.Archive's methods over PostgreSQL.

`Archive("postgresql://...")` returns this class (an `ArchiveReader`, as `Archive` is). The
session is read-only (the server refuses any write) and autocommit, so no read holds a transaction
open against the forwarders. A day is a partition; pages run in time order across stations (time,
station, the station's day and id), which for one station is its id order. Filters are the SQLite
ones, plus `Filter.stations`. The driver's errors leave it as `ArchiveError`.
"""

from __future__ import annotations

import csv
import datetime as dt
import functools
from collections.abc import Callable
from pathlib import Path
from typing import Concatenate, ParamSpec, TypeVar

import numpy as np
import psycopg

from app.scada.tag import Tag
from registrar.plant import schema as plant
from registrar.plant.url import url_problem
from registrar.reading import (
    EXPORT_CHUNK,
    ArchiveError,
    ArchiveReader,
    Filter,
    Row,
    SeriesKey,
    thinned,
    where_clause,
)
from registrar.schema import COLUMNS, GAP_SQL, TAG_FIELDS, table_name, tags_by_source

_SELECT = "SELECT " + ", ".join(COLUMNS) + ", station"
P = ParamSpec("P")
T = TypeVar("T")


def _reading(method: Callable[Concatenate[PgArchive, P], T]) -> Callable[Concatenate[PgArchive, P], T]:
    """The driver's errors of a read as ArchiveError naming the archive (the readers' callers
    know no psycopg)."""

    @functools.wraps(method)
    def read(self: PgArchive, *args: P.args, **kwargs: P.kwargs) -> T:
        try:
            return method(self, *args, **kwargs)
        except psycopg.Error as e:
            raise ArchiveError(f"{self.url}: {e}") from e

    return read


class PgArchive(ArchiveReader):
    def __init__(self, url: str) -> None:
        problem = url_problem(url)
        if problem:
            raise ValueError(f"{url}: {problem}")
        self.url = url
        try:
            self._pg = plant.connect(url, read_only=True)
        except psycopg.Error as e:
            raise ArchiveError(f"{url}: cannot open the plant archive: {e}") from None
        self._parts: dict[dt.date, str] = {}
        try:
            self.tz = plant.plant_zone(self._pg)
        except psycopg.Error as e:
            self._pg.close()
            why = ("no plant archive in this database (no station has forwarded to it yet)"
                   if isinstance(e, psycopg.errors.UndefinedTable) else f"cannot read the plant archive: {e}")
            raise ArchiveError(f"{url}: {why}") from None

    def close(self) -> None:
        self._pg.close()

    # --- days, stations and catalogues ---------------------------------------------------------

    @_reading
    def days(self) -> list[dt.date]:
        self._parts = plant.partitions(self._pg)
        return sorted(self._parts, reverse=True)

    @_reading
    def stations(self) -> list[str]:
        return [s for (s,) in self._pg.execute(
            "SELECT DISTINCT station FROM meta WHERE station <> %s ORDER BY station", (plant.PLANT,))]

    @_reading
    def meta(self, station: str | None = None) -> dict[str, str]:
        """The plant's meta, with a station's own over it (the only station's, if there is one)."""
        station = station or self._only_station()
        rows = self._pg.execute("SELECT key, value FROM meta WHERE station = %s OR station = %s "
                                "ORDER BY station = %s",
                                (plant.PLANT, station or plant.PLANT, station)).fetchall()
        return dict(rows)

    @_reading
    def message_texts(self, station: str | None = None) -> dict[int, str]:
        station = station or self._only_station()
        return dict(self._pg.execute("SELECT number, text FROM messages WHERE station = %s",
                                     (station,)).fetchall())

    @_reading
    def tags(self, station: str | None = None) -> dict[str, Tag]:
        """A station's current tags (the only station's, if there is one), as Archive.tags."""
        station = station or self._only_station()
        try:
            rows = self._pg.execute(f"SELECT {', '.join(TAG_FIELDS)} FROM tags WHERE station = %s "
                                    "AND valid_to = 'infinity' ORDER BY name", (station,)).fetchall()
        except psycopg.errors.UndefinedTable:  # a plant archive no station of this version wrote to
            return {}
        return tags_by_source(rows)

    def _only_station(self) -> str | None:
        stations = self.stations()
        return stations[0] if len(stations) == 1 else None

    @_reading
    def series_keys(self, day: dt.date) -> list[SeriesKey]:
        rows = self._pg.execute(
            "SELECT kind, grp, type, source, station FROM series WHERE day = %s "
            "ORDER BY kind, grp, type, source, station", (table_name(day),)).fetchall()
        return [SeriesKey(*r) for r in rows]

    # --- records -------------------------------------------------------------------------------

    @_reading
    def records(self, day: dt.date, flt: Filter | None = None, offset: int = 0, limit: int = 200,
                newest_first: bool = True) -> list[Row]:
        if limit <= 0 or not self._has(day):
            return []
        where, args = self._where(flt)
        order = "DESC" if newest_first else "ASC"
        rows = self._pg.execute(
            f'{_SELECT} FROM "{table_name(day)}"{where} '
            f"ORDER BY ts {order}, station {order}, day {order}, id {order} LIMIT %s OFFSET %s",
            [*args, limit, offset]).fetchall()
        return [Row(r[0], r[1] / 1000.0, *r[2:9], station=r[9], tz=self.tz) for r in rows]

    @_reading
    def count(self, day: dt.date, flt: Filter | None = None) -> int:
        if not self._has(day):
            return 0
        where, args = self._where(flt)
        return self._pg.execute(f'SELECT count(*) FROM "{table_name(day)}"{where}', args).fetchone()[0]

    @_reading
    def export_csv(self, path: str | Path, day: dt.date, flt: Filter | None = None) -> int:
        """The SQLite archive's CSV with the station as a last column, oldest first."""
        n = 0
        with open(path, "w", newline="", encoding="utf-8-sig") as f:
            out = csv.writer(f)
            out.writerow(["id", "time", *COLUMNS[1:], "station"])
            if not self._has(day):
                return 0
            where, args = self._where(flt)
            with self._pg.transaction(), self._pg.cursor(name="export") as cur:
                cur.execute(f'{_SELECT} FROM "{table_name(day)}"{where} ORDER BY ts, station, day, id',
                            args)
                while chunk := cur.fetchmany(EXPORT_CHUNK):
                    for r in chunk:
                        local = self.local_time(r[1] / 1000).isoformat(timespec="milliseconds")
                        out.writerow([r[0], local, *r[1:]])
                    n += len(chunk)
        return n

    # --- series --------------------------------------------------------------------------------

    @_reading
    def series(self, day: dt.date, *, grp: int | None = None, type: int | None = None,
               source: str | None = None, points: int = 1000,
               station: str | None = None) -> tuple[np.ndarray, np.ndarray]:
        """As Archive.series, of one station (or of every station's records of that key)."""
        empty = (np.empty(0), np.empty(0))
        if not self._has(day):
            return empty
        conds, args = ["kind = 'data'", f"(value IS NOT NULL OR {GAP_SQL})"], []
        for col, val in (("station", station), ("grp", grp), ("type", type), ("source", source)):
            if val is not None:
                conds.append(f"{col} = %s")
                args.append(val)
        with self._pg.cursor(binary=True) as cur:
            cur.execute(f'SELECT ts, coalesce(value, 0), {GAP_SQL} FROM "{table_name(day)}" '
                        f'WHERE {" AND ".join(conds)} ORDER BY ts', args)
            rows = cur.fetchall()
        if not rows:
            return empty
        data = np.array(rows, dtype=[("ts", "i8"), ("value", "f8"), ("gap", "?")])
        return thinned(data["ts"] / 1000.0, np.where(data["gap"], np.nan, data["value"]), points)

    # --- helpers -------------------------------------------------------------------------------

    def _where(self, flt: Filter | None) -> tuple[str, list[object]]:
        flt = flt or Filter()
        where, args = where_clause(flt, "%s")
        if flt.stations is not None:
            stations = sorted(flt.stations)
            cond = f"station IN ({', '.join(['%s'] * len(stations))})" if stations else "1 = 0"
            where = f"{where} AND {cond}" if where else f" WHERE {cond}"
            args += stations
        return where, args

    def _has(self, day: dt.date) -> bool:
        if day not in self._parts:
            self._parts = plant.partitions(self._pg)
        return day in self._parts
