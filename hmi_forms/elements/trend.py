"""A fixed-size ring buffer of samples for trend displays (Graph and AnalogBase "graph").

pyqtgraph has no append API, so trends keep a preallocated float64 buffer and hand an ordered
copy to `setData` only when a redraw is due (docs/architecture.md section 9). NaN marks a sample taken while
the data were stale, which the plot draws as a gap.
"""

from __future__ import annotations

import numpy as np


class Trend:
    def __init__(self, size: int) -> None:
        self.size = size
        self.buf = np.full(size, np.nan)
        self.count = 0  # samples ever added
        self.x = np.arange(size, dtype=np.float64)

    def add(self, value: float) -> None:
        self.buf[self.count % self.size] = value
        self.count += 1

    def values(self) -> np.ndarray:
        """The stored samples, oldest first (at most `size`)."""
        if self.count <= self.size:
            return self.buf[: self.count].copy()
        i = self.count % self.size
        return np.concatenate((self.buf[i:], self.buf[:i]))

    @property
    def last(self) -> float:
        return float(self.buf[(self.count - 1) % self.size]) if self.count else float("nan")
