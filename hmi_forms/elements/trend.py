"""A fixed-size ring buffer of samples for trend displays (Graph and AnalogBase "graph").

pyqtgraph has no append API, so trends keep a preallocated float64 buffer and hand an ordered
copy to `setData` only when a redraw is due (docs/architecture.md section 9). NaN marks a sample taken while
the data were stale, which the plot draws as a gap. Each sample keeps the wall-clock time of its
scan, so the trends of a form share one clock-time axis and join the archive's history.
"""

from __future__ import annotations

import math

from netplc.lazy import lazy

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it


class Trend:
    def __init__(self, size: int) -> None:
        self.size = size
        self.buf = np.full(size, np.nan)
        self.t = np.full(size, np.nan)  # wall-clock seconds of each sample
        self.count = 0  # samples ever added

    def add(self, value: float, t: float = math.nan) -> None:
        i = self.count % self.size
        self.buf[i] = value
        self.t[i] = t
        self.count += 1

    def _ordered(self, buf: np.ndarray) -> np.ndarray:
        if self.count <= self.size:
            return buf[: self.count].copy()
        i = self.count % self.size
        return np.concatenate((buf[i:], buf[:i]))

    def values(self) -> np.ndarray:
        """The stored samples, oldest first (at most `size`)."""
        return self._ordered(self.buf)

    def times(self) -> np.ndarray:
        """The wall-clock times of `values()`."""
        return self._ordered(self.t)

    @property
    def last(self) -> float:
        return float(self.buf[(self.count - 1) % self.size]) if self.count else float("nan")
