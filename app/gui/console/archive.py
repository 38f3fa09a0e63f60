"""The station's archive as a console reads it: its Historical Access behind the archive readers'
interface (registrar/reading.py `ArchiveReader`), so that every view of an archive (a form's
trend history, the run-time trend window, the offline viewer's records and series) has one code
path whether the archive is a file at hand or a station's over OPC UA. Qt-free.

- A series is an archived tag's history (HistoryReadRawModified of `Tags/<name>`, the station's
  pages read on), keyed as in the station's own archive by the octal address its NSTORE stores
  (`SeriesKey("data", grp, type, "04010")`). The station answers physical values; the reader
  gives back the words the archive holds (the tag's own conversion: `to_raw`, `encode`), so the
  views convert once, as from a file. A value not good is a gap (NaN).
- Records are the journal's events (HistoryReadEvents on the station object): the time range is
  the read's domain, and the station evaluates the rest of the filter as the where clause
  (app/publish/history.py `journal_where`): a minimum type as a minimum Severity, an exact source
  as SourceName, "text contains" as Like on the Message in the spellings the local archive tries.
  Kinds are told apart from the events' types on the console; a message's group is not in its
  event (`unfiltered`). Data records are the series': the Records page of a station holds its
  journal only.
- Days are those from the journal's first event to today (the station has no call that lists its
  archive's days): a day without records reads as empty.

A reader holds the last day and filter it read (the viewer pages through them without asking the
station again); readers of one console share its session (`StationArchiveSource.open`).
"""

from __future__ import annotations

import csv
import datetime as dt
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from app.publish.console import ConsoleClient
from app.publish.history import ARCHIVED_TYPES, JOURNAL
from app.scada.table import TagTable
from app.scada.tag import Tag
from netplc.address import fmt_octal
from registrar.reading import ArchiveReader, Filter, Row, SeriesKey, thinned
from registrar.schema import COLUMNS

READ_S = 60.0  # an answer (all its pages) the station does not give within this is a failed read
MAX_RECORDS = 100_000  # of one day and filter: what the viewer pages through
MAX_DAYS = 366  # listed back from today
FIRST = dt.datetime(1601, 1, 2, tzinfo=dt.UTC)  # before any record: the journal's first event from here


def _day_range(day: dt.date, flt: Filter) -> tuple[dt.datetime, dt.datetime]:
    """The day (this machine's) within the filter's From/To."""
    t0 = dt.datetime.combine(day, dt.time.min).astimezone().timestamp()
    t1 = dt.datetime.combine(day + dt.timedelta(days=1), dt.time.min).astimezone().timestamp()
    if flt.since is not None:
        t0 = max(t0, flt.since)
    if flt.until is not None:
        t1 = min(t1, flt.until)
    return dt.datetime.fromtimestamp(t0, dt.UTC), dt.datetime.fromtimestamp(max(t0, t1), dt.UTC)


@dataclass(eq=False)  # one console's archive is itself, whatever its tags
class StationArchiveSource:
    """A station's archive as `registrar.query.Archive` opens it at a console (an `ArchiveSource`):
    its session and its tags (as its files give them); the tags it historizes asked once."""

    client: ConsoleClient
    tags: TagTable
    _archived: dict[str, Tag] | None = field(default=None, repr=False)

    def open(self) -> StationArchive:
        return StationArchive(self)

    def available(self) -> bool:
        """The link up: a view that asked while it was down asks again when it next wants."""
        return not self.client.error

    def archived(self) -> dict[str, Tag]:
        """The tags the station keeps the history of, by the octal address their NSTORE stores."""
        if self._archived is None:
            words = [t for t in self.tags.tags if t.type in ARCHIVED_TYPES]
            kept = self.client.historizing([t.name for t in words]).result(READ_S)
            self._archived = {fmt_octal(t.address): t for t in words if t.name in kept}
        return self._archived

    def __str__(self) -> str:
        return f"{self.client.where()} ({self.client.url})"


class StationArchive(ArchiveReader):
    def __init__(self, source: StationArchiveSource) -> None:
        self.source = source
        self.client = source.client
        self._read: tuple[dt.date, Filter, list[Row]] | None = None  # oldest first
        self.unfiltered = frozenset({"grp"})  # a message's group is not in its event

    def close(self) -> None:
        pass  # the session is the console's

    def days(self) -> list[dt.date]:
        first = self.client.events(FIRST, dt.datetime.now(dt.UTC) + dt.timedelta(days=1),
                                   Filter(), 1).result(READ_S)
        today = dt.date.today()
        oldest = max(first[0].time.date(), today - dt.timedelta(days=MAX_DAYS - 1)) if first else today
        return [today - dt.timedelta(days=k) for k in range((today - oldest).days + 1)]

    def tags(self) -> dict[str, Tag]:
        return self.source.archived()

    # --- records ---------------------------------------------------------------------------------

    def _rows(self, day: dt.date, flt: Filter) -> list[Row]:
        if self._read is not None and self._read[:2] == (day, flt):
            return self._read[2]
        rows: list[Row] = []
        if flt.kinds is None or set(flt.kinds) & set(JOURNAL):
            start, end = _day_range(day, flt)
            if start < end:
                rows = [r for r in self.client.events(start, end, flt, MAX_RECORDS).result(READ_S)
                        if flt.kinds is None or r.kind in flt.kinds]
        self._read = (day, flt, rows)
        return rows

    def records(self, day: dt.date, flt: Filter | None = None, offset: int = 0, limit: int = 200,
                newest_first: bool = True) -> list[Row]:
        rows = self._rows(day, flt or Filter())
        if newest_first:
            rows = rows[::-1]
        return rows[offset:offset + limit]

    def count(self, day: dt.date, flt: Filter | None = None) -> int:
        return len(self._rows(day, flt or Filter()))

    def export_csv(self, path: str | Path, day: dt.date, flt: Filter | None = None) -> int:
        """As the local archive's export (registrar/query.py): its columns, oldest first."""
        rows = self._rows(day, flt or Filter())
        with open(path, "w", newline="", encoding="utf-8-sig") as f:
            out = csv.writer(f)
            out.writerow(["id", "time", *COLUMNS[1:], "tag", "physical", "unit"])
            for r in rows:
                local = self.local_time(r.ts).isoformat(timespec="milliseconds")
                out.writerow([r.id, local, round(r.ts * 1000), r.kind, r.grp, r.type, r.source, r.number,
                              r.value, r.text, "", "", ""])
        return len(rows)

    # --- series ----------------------------------------------------------------------------------

    def series_keys(self, day: dt.date) -> list[SeriesKey]:
        return [SeriesKey("data", None, None, source) for source in sorted(self.source.archived())]

    def series(self, day: dt.date, *, grp: int | None = None, type: int | None = None,
               source: str | None = None, points: int = 1000) -> tuple[np.ndarray, np.ndarray]:
        tag = self.source.archived().get(source or "")
        if tag is None:  # an element's own series, or a word the station does not archive
            return np.empty(0), np.empty(0)
        start, end = _day_range(day, Filter())
        values = self.client.history(tag.name, start, end).result(READ_S)
        ts = np.array([v.SourceTimestamp.timestamp() for v in values], dtype=np.float64)
        words = np.array([_word(tag, v) for v in values], dtype=np.float64)
        order = np.argsort(ts, kind="stable")
        return thinned(ts[order], words[order], points)


def _word(tag: Tag, value: Any) -> float:
    """The archive's word of a value (a DataValue) the station answered in physical units (NaN:
    not good)."""
    if not value.StatusCode.is_good() or value.Value is None or value.Value.Value is None:
        return math.nan
    return float(int.from_bytes(tag.encode(tag.to_raw(float(value.Value.Value))), "little"))
