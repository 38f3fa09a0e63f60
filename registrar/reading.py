"""What both archive readers share: the filter, the rows and series keys they return, the WHERE
clause of a filter, and the min/max thinning of a series. The station's SQLite archive
(registrar/query.py) and the plant archive on PostgreSQL (registrar/plant/query.py) each build on it,
so neither imports the other's driver.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from typing import NamedTuple, Protocol

from app.scada.tag import Tag
from netplc.lazy import lazy

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it

EXPORT_CHUNK = 10_000


class ArchiveError(Exception):
    """The plant archive cannot be opened or read (PostgreSQL away, no such database, a dropped
    connection). registrar/plant raises it for its driver's errors, so that the viewer and the
    commands catch them without importing psycopg; the SQLite reader raises sqlite3.Error."""


@dataclass(frozen=True)
class Filter:
    kinds: set[str] | frozenset[str] | None = None
    grp: int | None = None
    type: int | None = None  # a message type (`type_clause`: alarm records by its priority)
    min_type: int | None = None  # e.g. 2: alarms and worse (messages and alarm records only)
    source: str | None = None
    text: str | None = None  # contains
    since: float | None = None  # seconds since the epoch, inclusive
    until: float | None = None  # seconds since the epoch, exclusive
    stations: set[str] | frozenset[str] | None = None  # plant archive: these stations only


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
    station: str | None = None  # plant archive: the station that wrote it
    tz: dt.tzinfo | None = None  # the zone the archive's days are cut in (None: this machine's)

    @property
    def time(self) -> dt.datetime:
        """Wall time of the record where it was written (naive)."""
        return dt.datetime.fromtimestamp(self.ts, self.tz).replace(tzinfo=None)


class SeriesKey(NamedTuple):
    kind: str
    grp: int | None
    type: int | None
    source: str | None
    station: str | None = None  # plant archive: whose series


class ArchiveReader:
    """What every archive reader answers besides its queries: its zone, its stations, local times,
    and the fields of a `Filter` it cannot apply (`unfiltered`: the viewer offers them not)."""

    tz: dt.tzinfo | None = None
    unfiltered: frozenset[str] = frozenset()

    def stations(self) -> list[str]:
        """The stations that write to the archive: a station's own archive names none."""
        return []

    def tags(self) -> dict[str, Tag]:
        """The one-word tags by the `source` of their data records ({}: none kept)."""
        return {}

    def local_time(self, ts: float) -> dt.datetime:
        return dt.datetime.fromtimestamp(ts, self.tz).replace(tzinfo=None)

    def close(self) -> None:
        raise NotImplementedError

    def __enter__(self) -> ArchiveReader:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class ArchiveSource(Protocol):
    """An archive reached otherwise than by a file or a URL: a station's Historical Access at a
    remote console (app/gui/console/archive.py). `registrar.query.Archive` opens it with `open`;
    `available` is False while it cannot be read (a station out of reach)."""

    def open(self) -> ArchiveReader: ...

    def available(self) -> bool: ...


def where_clause(flt: Filter, mark: str = "?") -> tuple[str, list[object]]:
    """The WHERE clause of a filter; `mark` is the driver's placeholder (psycopg: %s)."""
    conds: list[str] = []
    args: list[object] = []
    if flt.kinds is not None:
        kinds = sorted(flt.kinds)
        conds.append(f"kind IN ({', '.join([mark] * len(kinds))})" if kinds else "1 = 0")
        args.extend(kinds)
    for col, val in (("grp", flt.grp), ("source", flt.source)):
        if val is not None:
            conds.append(f"{col} = {mark}")
            args.append(val)
    if flt.type is not None:
        conds.append(f"((kind = 'alarm' AND grp = {mark}) OR (kind <> 'alarm' AND type = {mark}))")
        args += [alarm_priority(flt.type), flt.type]
    if flt.min_type is not None:
        conds.append(f"((kind = 'message' AND type >= {mark}) OR (kind = 'alarm' AND grp <= {mark}))")
        args += [flt.min_type, alarm_priority(flt.min_type)]
    if flt.since is not None:
        conds.append(f"ts >= {mark}")
        args.append(round(flt.since * 1000))
    if flt.until is not None:
        conds.append(f"ts < {mark}")
        args.append(round(flt.until * 1000))
    if flt.text:
        variants = spellings(flt.text)
        likes = " OR ".join(f"text LIKE {mark} ESCAPE '\\'" for _ in variants)
        conds.append(f"text IS NOT NULL AND ({likes})")
        args.extend(f"%{_escape_like(v)}%" for v in variants)
    return (" WHERE " + " AND ".join(conds)) if conds else "", args


def spellings(text: str) -> list[str]:
    """What "text contains" looks for: SQLite folds case for ASCII only (and a Like of OPC UA for
    none), so the usual spellings of a Cyrillic word are tried too."""
    return sorted({text, text.lower(), text.upper(), text.capitalize()})


def alarm_priority(message_type: int) -> int:
    """The alarm priority of a message type's severity, for a type filter over `alarm` records,
    whose type column is the alarm's new state and whose grp is its priority: 3 critical ->
    priority 1 and 2 alarm -> 2 (as NMSG's alarms are raised, app/scada/alarms.py), 1 warning ->
    3 (medium), 0 info -> 4 (low). A minimum type is then a maximum priority number, and records
    of other kinds than message and alarm (operator, system, data) have no severity to pass it."""
    return 4 - message_type


def _escape_like(text: str) -> str:
    return text.replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_")


def thinned(ts: np.ndarray, values: np.ndarray, points: int) -> tuple[np.ndarray, np.ndarray]:
    """A series in time order reduced to about `points` points by `min_max`. A NaN is a gap (a
    record whose value was not good, registrar/schema.py GAP_SQL): the first of each run of them
    is kept where it was, so a plot breaks its line there, and the values between are reduced."""
    gap = np.isnan(values)
    if gap.any():
        keep = ~gap | np.r_[True, ~gap[:-1]]  # the values and the first NaN of each run
        ts, values, gap = ts[keep], values[keep], gap[keep]
    if len(ts) <= points:
        return ts, values
    buckets = max(1, points // 2)
    if not gap.any():
        return min_max(ts, values, buckets)
    good_ts, good = (min_max(ts[~gap], values[~gap], buckets) if not gap.all()
                     else (np.empty(0), np.empty(0)))
    ts = np.concatenate((good_ts, ts[gap]))
    values = np.concatenate((good, values[gap]))
    order = np.argsort(ts, kind="stable")
    return ts[order], values[order]


def min_max(ts: np.ndarray, values: np.ndarray, buckets: int) -> tuple[np.ndarray, np.ndarray]:
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
