"""Run-time trends: what an operator saved (named trends of pens, per user) and what a trend says
about the range it shows (values at the cursors, minimum, maximum, mean, the CSV of its points).

The saved trends live in `trends.json` beside the station's archive, the folder the station writes
(as the workstation's `workstation.ini`): a trend is the operator's, kept with the station and its
history rather than in a profile of the PC's account, so it is there on whichever workstation
account runs the station, and a backup of the station's archive folder carries it. One file for
all users, each user's trends under their name, written whole (a temporary file then a rename),
so a crash never leaves half a file.
"""

from __future__ import annotations

import datetime as dt
import json
import math
import os
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

FILE = "trends.json"
COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf")
SPANS = (600.0, 3600.0, 8 * 3600.0, 86_400.0)  # the spans offered: 10 min, 1 h, 8 h, a day


class TrendFileError(ValueError):
    """The trends file cannot be read: its path and why."""


@dataclass(frozen=True)
class Pen:
    tag: str
    colour: str


@dataclass
class SavedTrend:
    name: str
    pens: list[Pen] = field(default_factory=list)
    span: float = 3600.0  # seconds shown when the trend follows the live values


def colour_for(taken: Sequence[str]) -> str:
    """The first colour of the palette no pen has yet (the palette again once all are taken)."""
    return next((c for c in COLOURS if c not in taken), COLOURS[len(taken) % len(COLOURS)])


class TrendBook:
    """The named trends of each user of a station."""

    def __init__(self, folder: Path) -> None:
        self.path = folder / FILE

    def _load(self) -> dict[str, dict[str, dict]]:
        if not self.path.exists():
            return {}
        try:
            data = json.loads(self.path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as e:
            raise TrendFileError(f"{self.path}: {e}") from e
        if not isinstance(data, dict) or not all(isinstance(v, dict) for v in data.values()):
            raise TrendFileError(f"{self.path}: not an object of users, each an object of trends")
        return data

    def names(self, user: str) -> list[str]:
        return sorted(self._load().get(user, {}))

    def get(self, user: str, name: str) -> SavedTrend | None:
        raw = self._load().get(user, {}).get(name)
        if raw is None:
            return None
        try:
            pens = [Pen(str(p["tag"]), str(p["colour"])) for p in raw["pens"]]
            return SavedTrend(name, pens, float(raw.get("span", 3600.0)))
        except (KeyError, TypeError, ValueError) as e:
            raise TrendFileError(f"{self.path}: trend {name!r} of {user!r}: {e!r}") from e

    def put(self, user: str, trend: SavedTrend) -> None:
        data = self._load()
        data.setdefault(user, {})[trend.name] = {"pens": [asdict(p) for p in trend.pens], "span": trend.span}
        self.path.parent.mkdir(parents=True, exist_ok=True)
        part = self.path.with_suffix(".json.part")
        part.write_text(json.dumps(data, ensure_ascii=False, indent=1), encoding="utf-8")
        os.replace(part, self.path)


@dataclass(frozen=True)
class Stats:
    min: float
    max: float
    mean: float


def value_at(ts: np.ndarray, values: np.ndarray, t: float) -> float:
    """The value a pen held at `t`: its last sample at or before it (the archive records a change
    or a period's value, held until the next); NaN before the first or inside a gap."""
    i = int(np.searchsorted(ts, t, side="right")) - 1
    return float(values[i]) if i >= 0 else math.nan


def stats(ts: np.ndarray, values: np.ndarray, t0: float, t1: float) -> Stats | None:
    """Minimum, maximum and mean of the samples in [t0, t1] (gaps left out); None if none. The
    mean is of the samples, as the archive reduced them (a day is read as bucket minima and maxima)."""
    inside = values[(ts >= t0) & (ts <= t1)]
    inside = inside[~np.isnan(inside)]
    if not len(inside):
        return None
    return Stats(float(inside.min()), float(inside.max()), float(inside.mean()))


def csv_rows(pens: Sequence[tuple[str, np.ndarray, np.ndarray]], t0: float, t1: float) -> list[list[str]]:
    """The samples of every pen in [t0, t1], one row per time any pen has a sample: the local time
    with milliseconds, then each pen's value at that time (empty where it has none). `pens` are
    (heading, times, values)."""
    times = sorted({float(t) for _, ts, _ in pens for t in ts[(ts >= t0) & (ts <= t1)]})
    columns = []
    for _, ts, values in pens:
        at = {float(t): v for t, v in zip(ts, values, strict=True) if t0 <= t <= t1}
        columns.append(at)
    rows = [["time", *(heading for heading, _, _ in pens)]]
    for t in times:
        cells = [("" if (v := col.get(t)) is None or math.isnan(v) else f"{v:.6g}") for col in columns]
        rows.append([dt.datetime.fromtimestamp(t).isoformat(sep=" ", timespec="milliseconds"), *cells])
    return rows
