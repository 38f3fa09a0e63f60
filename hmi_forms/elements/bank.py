"""The words of a form's plain analog elements, read and compared as one array per snapshot.

A form of a thousand gauges reads a thousand words per tick; asking each element's own reader
costs a Python call, a closure and a comparison per element whether the word moved or not. A
bank gathers them all with one numpy index into the snapshot's bytes and reports only those that
changed since they were last taken, so Python runs for what is really new.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from netplc.address import DATA_SIZE, data_index

UNKNOWN = -1  # not a word: taken again at the next snapshot, whatever it holds


class WordBank:
    """Little-endian words at data addresses (validated by the form's loader)."""

    def __init__(self, addresses: Sequence[int]) -> None:
        index = np.array([data_index(a) for a in addresses], dtype=np.intp)
        if len(index) and int(index.max()) + 1 >= DATA_SIZE:
            raise ValueError("a word's high byte lies past the end of data memory")
        self.aligned = not (index % 2).any()  # read as one array of words: one gather
        self.index = index // 2 if self.aligned else index
        self.last = np.full(len(index), UNKNOWN, dtype=np.int32)

    def __len__(self) -> int:
        return len(self.last)

    def changed(self, data: bytes) -> tuple[list[int], list[int]]:
        """The positions whose word differs from the one last taken, and their new words."""
        if self.aligned:
            words = np.frombuffer(data, dtype="<u2")[self.index]
        else:
            raw = np.frombuffer(data, dtype=np.uint8)
            words = raw[self.index] | raw[self.index + 1].astype(np.uint16) << 8
        where = np.flatnonzero(words != self.last)
        self.last[where] = words[where]
        return where.tolist(), words[where].tolist()

    def forget(self, position: int) -> None:
        """Report the word at `position` at the next snapshot even if it did not change."""
        self.last[position] = UNKNOWN
