"""A fixed-size ring buffer of samples for trend displays (Graph and AnalogBase "graph").

The samples live in preallocated float64 buffers, each sample written twice (at i and i + size), so
that the kept samples, oldest first, are always one contiguous slice: a trend's redraw reads them
without a copy (hmi_forms/widgets/trend.py). NaN marks a sample taken while the data were stale,
which the plot draws as a gap; `gaps` counts them, so a redraw of a trend without any looks for
none. Each sample keeps the wall-clock time of its scan, so the trends of a form share one time
axis and join the archive's history.
"""

from __future__ import annotations

import math

from netplc.lazy import lazy

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it


class Trend:
    def __init__(self, size: int) -> None:
        self.size = size
        self.buf = np.full(2 * size, np.nan)
        self.t = np.full(2 * size, np.nan)  # wall-clock seconds of each sample
        self.count = 0  # samples ever added
        self.gaps = 0  # kept samples whose value or time is NaN

    def add(self, value: float, t: float = math.nan) -> None:
        i, size = self.count % self.size, self.size
        if self.count >= size and (math.isnan(self.buf[i]) or math.isnan(self.t[i])):
            self.gaps -= 1  # a gap drops out of the window
        if math.isnan(value) or math.isnan(t):
            self.gaps += 1
        self.buf[i] = self.buf[i + size] = value
        self.t[i] = self.t[i + size] = t
        self.count += 1

    def _kept(self, buf: np.ndarray) -> np.ndarray:
        if self.count <= self.size:
            return buf[: self.count]
        i = self.count % self.size
        return buf[i: i + self.size]

    def values(self) -> np.ndarray:
        """The kept samples, oldest first (at most `size`): a view of the buffer, not to be changed."""
        return self._kept(self.buf)

    def times(self) -> np.ndarray:
        """The wall-clock times of `values()` (a view, too)."""
        return self._kept(self.t)

    @property
    def last(self) -> float:
        return float(self.buf[(self.count - 1) % self.size]) if self.count else float("nan")
