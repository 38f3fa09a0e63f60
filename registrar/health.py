"""Alarm-system health as ISA-18.2 measures it, computed from the journal's 'alarm' records.

For one local day: the alarms per 10 minutes (a flood is 10 or more in 10 minutes), the 10 most
frequent alarms, the chattering ones (3 or more activations within 60 s) and the stale ones
(continuously active for more than 24 hours at the end of the day, or now for today). An alarm
is counted each time it is annunciated: every transition into active-unacknowledged.
Stale alarms may have come days before, so the earlier days of the archive are read for them.
"""

from __future__ import annotations

import datetime as dt
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field

from app.scada.alarms import State
from registrar.query import Archive, Filter, Row
from registrar.schema import local_day_bounds

SLOT = 600.0  # seconds: ISA-18.2 counts alarms per 10 minutes
FLOOD = 10  # alarms in one slot
CHATTER_COUNT = 3  # activations ...
CHATTER_WINDOW = 60.0  # ... within this many seconds
STALE_AFTER = 24 * 3600.0
TOP = 10
PAGE = 10_000
ACTIVE = (State.UNACK, State.ACKED)
ALARMS = Filter(kinds=frozenset({"alarm"}))


@dataclass
class AlarmHealth:
    day: dt.date
    activations: int = 0
    slots: list[int] = field(default_factory=list)  # activations per 10 minutes from local midnight
    top: list[tuple[str, int, str]] = field(default_factory=list)  # alarm, activations, text
    chattering: list[tuple[str, int, float]] = field(default_factory=list)  # alarm, most in 60 s, when
    stale: list[tuple[str, float, float]] = field(default_factory=list)  # alarm, active since, hours
    start: float = 0.0  # local midnight, epoch seconds

    @property
    def floods(self) -> list[tuple[float, int]]:
        """(start of the slot, activations) of every 10 minutes in flood."""
        return [(self.start + k * SLOT, n) for k, n in enumerate(self.slots) if n >= FLOOD]

    def lines(self) -> list[str]:
        """The report as `main.py alarms-report` prints it."""
        def hm(ts: float, fmt: str = "%H:%M:%S") -> str:
            return dt.datetime.fromtimestamp(ts).strftime(fmt)

        busy = [n for n in self.slots if n]
        mean = self.activations / len(self.slots) if self.slots else 0.0
        out = [f"alarm-system health for {self.day:%d.%m.%Y}",
               f"alarms: {self.activations}; per 10 minutes: mean {mean:.1f}, "
               f"most {max(self.slots, default=0)} ({len(busy)} of {len(self.slots)} periods with alarms)"]
        floods = self.floods
        out.append(f"floods (>= {FLOOD} alarms in 10 minutes): {len(floods)}"
                   + (f", {100 * len(floods) / len(self.slots):.1f} % of the day" if self.slots else ""))
        out += [f"  {hm(start)}-{hm(start + SLOT)}  {n} alarms" for start, n in floods]
        out.append(f"top {TOP} most frequent alarms:" if self.top else "top 10 most frequent alarms: none")
        out += [f"  {n:6d}  {alarm}  {text}" for alarm, n, text in self.top]
        out.append(f"chattering (>= {CHATTER_COUNT} activations in {CHATTER_WINDOW:g} s): "
                   f"{len(self.chattering)}")
        out += [f"  {alarm}: {n} activations in 60 s from {hm(at)}" for alarm, n, at in self.chattering]
        out.append(f"stale (active for more than 24 h): {len(self.stale)}")
        out += [f"  {alarm}: active since {hm(since, '%d.%m.%Y %H:%M:%S')} ({hours:.1f} h)"
                for alarm, since, hours in self.stale]
        return out


def _rows(archive: Archive, day: dt.date) -> Iterator[Row]:
    """The day's alarm records, oldest first."""
    offset = 0
    while True:
        page = archive.records(day, ALARMS, offset, PAGE, newest_first=False)
        yield from page
        if len(page) < PAGE:
            return
        offset += PAGE


def _text(row: Row) -> str:
    """The alarm's own text out of a transition's ('ID old -> new: TEXT; ...')."""
    text = row.text or ""
    return text.split(": ", 1)[1].split("; ")[0] if ": " in text else text


def alarm_health(archive: Archive, day: dt.date, now: float | None = None) -> AlarmHealth:
    _, start, end = local_day_bounds(dt.datetime(day.year, day.month, day.day, 12).timestamp())
    report = AlarmHealth(day, start=start)
    report.slots = [0] * round((end - start) / SLOT)
    times: dict[str, list[float]] = {}
    texts: dict[str, str] = {}
    for row in _rows(archive, day):
        texts[row.source or ""] = _text(row)
        if row.type == State.UNACK:
            times.setdefault(row.source or "", []).append(row.ts)
            report.activations += 1
            report.slots[min(int((row.ts - start) // SLOT), len(report.slots) - 1)] += 1
    counts = Counter({alarm: len(ts) for alarm, ts in times.items()})
    report.top = [(alarm, n, texts.get(alarm, "")) for alarm, n in
                  sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))[:TOP]]
    for alarm, ts in sorted(times.items()):
        most, when, first = 0, 0.0, 0
        for last, t in enumerate(ts):
            while t - ts[first] > CHATTER_WINDOW:
                first += 1
            if last - first + 1 > most:
                most, when = last - first + 1, ts[first]
        if most >= CHATTER_COUNT:
            report.chattering.append((alarm, most, when))
    at = end if now is None else min(end, now)
    report.stale = _stale(archive, day, at)
    return report


def _stale(archive: Archive, day: dt.date, at: float) -> list[tuple[str, float, float]]:
    """Alarms active without a break for more than 24 h at `at`, from this and the earlier days."""
    since: dict[str, float | None] = {}  # alarm -> the start of its current activity, None if not active
    for d in sorted(x for x in archive.days() if x <= day):
        for row in _rows(archive, d):
            if row.ts >= at:
                break
            alarm = row.source or ""
            if row.type in ACTIVE:
                if row.number not in ACTIVE or since.get(alarm) is None:
                    since[alarm] = row.ts
            else:
                since[alarm] = None
    return sorted(((alarm, t, (at - t) / 3600) for alarm, t in since.items()
                   if t is not None and at - t > STALE_AFTER), key=lambda x: x[1])
