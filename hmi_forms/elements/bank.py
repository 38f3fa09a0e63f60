"""The operands of a form's plain elements, read and compared as one array per snapshot.

A form of a thousand gauges and lamps reads a thousand operands per tick; asking each element's
own reader costs a Python call, a closure and a comparison per element whether the value moved or
not. A bank gathers them all with one numpy index into the snapshot and reports only those that
changed since they were last taken, so Python runs for what is really new. The elements a bank
serves are those whose value is all they show (`plain`): each model `settle`s what the bank read,
and what draws it is handed what it shows now.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from operator import itemgetter
from typing import Any, Protocol

from app.scada.quality import Operands, Quality, QualityMap
from app.scada.readings import Readings
from hmi_forms.elements.base import Element
from netplc.address import DATA_SIZE, IO_BITS, data_index
from netplc.lazy import lazy
from netplc.memory import Snapshot

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it

UNKNOWN = -1  # no value: taken again at the next snapshot, whatever it holds


class Bank:
    """Values last taken, and what changed since."""

    def __init__(self, size: int) -> None:
        self.last = np.full(size, UNKNOWN, dtype=np.int32)

    def read(self, snap: Snapshot) -> np.ndarray:
        raise NotImplementedError

    def changed(self, snap: Snapshot) -> tuple[list[int], list[int]]:
        """The positions whose value differs from the one last taken, and their new values."""
        values = self.read(snap)
        where = np.flatnonzero(values != self.last)
        np.copyto(self.last, values)  # (a tick of a large form runs cold: each numpy call counts)
        return where.tolist(), values[where].tolist()

    def forget(self, position: int) -> None:
        """Report the value at `position` at the next snapshot even if it did not change."""
        self.last[position] = UNKNOWN


class WordBank(Bank):
    """Little-endian words at data addresses (validated by the form's loader)."""

    def __init__(self, addresses: Sequence[int]) -> None:
        super().__init__(len(addresses))
        index = np.array([data_index(a) for a in addresses], dtype=np.intp)
        if len(index) and int(index.max()) + 1 >= DATA_SIZE:
            raise ValueError("a word's high byte lies past the end of data memory")
        self.aligned = not (index % 2).any()  # read as one array of words: one gather
        self.index = index // 2 if self.aligned else index

    def read(self, snap: Snapshot) -> np.ndarray:
        if self.aligned:
            return np.frombuffer(snap.data, dtype="<u2")[self.index]
        raw = np.frombuffer(snap.data, dtype=np.uint8)
        return raw[self.index] | raw[self.index + 1].astype(np.uint16) << 8


class BitBank(Bank):
    """HMI bits: I/O bits (< 04000) and bits of data bytes (`byte*8 + bit`)."""

    def __init__(self, hmi_bits: Sequence[int]) -> None:
        super().__init__(len(hmi_bits))
        io = [(i, b) for i, b in enumerate(hmi_bits) if b < IO_BITS]
        data = [(i, b) for i, b in enumerate(hmi_bits) if b >= IO_BITS]
        self.io_at = np.array([i for i, _ in io], dtype=np.intp)
        # itemgetter of one index gives the item, not a tuple: ask for it twice, use the first
        picks = [b for _, b in io]
        self.io_get = itemgetter(*picks) if len(picks) > 1 else itemgetter(*picks * 2) if picks else None
        self.io_count = len(picks)
        self.data_at = np.array([i for i, _ in data], dtype=np.intp)
        self.byte = np.array([data_index(b >> 3) for _, b in data], dtype=np.intp)
        self.shift = np.array([b & 7 for _, b in data], dtype=np.uint8)
        self.values = np.zeros(len(hmi_bits), dtype=np.int32)

    def read(self, snap: Snapshot) -> np.ndarray:
        values = self.values
        if self.io_get is not None:
            picked = np.array(self.io_get(snap.bits), dtype=bool)[:self.io_count]
            values[self.io_at] = picked
        if len(self.byte):
            raw = np.frombuffer(snap.data, dtype=np.uint8)
            values[self.data_at] = raw[self.byte] >> self.shift & 1
        return values


class Draws(Protocol):
    rect: Any

    def put(self, shown: Any) -> bool: ...


class Banked:
    """The elements one bank serves, refreshed from each snapshot: only those whose operand
    changed are settled (`Element.settle`), and what each shows then is handed to what draws it
    (`put`, True when the caller is to repaint the element). With the
    runtime's readings, the quality of all of them is judged at once (`Readings.judge`); one
    whose data are not good takes the general path (`Element.update`, then `sync`) and is taken
    anew from the bank once they are good again."""

    def __init__(self, kind: Callable[[list[int]], Bank], models: Sequence[Element], faces: Sequence[Draws],
                 syncs: Sequence[Callable[[], None]], fault: Callable[[Element, Exception], None]) -> None:
        """`kind` the bank that reads the operands; `faces` are what draw the elements
        (hmi_forms/widgets/base.py): each draws what its model settled (`put`) and is where it is
        repainted (`rect`)."""
        self.models, self.faces, self.syncs = list(models), list(faces), list(syncs)
        self.sources = [m.sources()[0] for m in self.models]  # a plain element shows one operand
        self.bank = kind([address for address, _ in self.sources])
        self.puts = [f.put for f in self.faces]
        kinds = {type(m) for m in self.models}  # many settled at once (`Element.settler`)
        self.settle = (kinds.pop() if len(kinds) == 1 else Element).settler(self.models)
        self.fault = fault
        self.marked = np.zeros(len(self.models), dtype=bool)  # shown with a quality mark
        self.judged_by: QualityMap | None = None
        self.operands: Operands | None = None
        self.links: list[int] = []  # link output bits: judged by their own rule, one by one

    def refresh(self, snap: Snapshot, readings: Readings | None) -> list[int]:
        """Take the snapshot; the positions of the elements the caller is to repaint."""
        positions, values = self.bank.changed(snap)
        if readings is None:
            codes = None
            general = np.flatnonzero(self.marked)  # marked once: cleared by the general path
        else:
            codes = self._judge(readings)
            general = np.flatnonzero((codes != Quality.GOOD) | self.marked)
        if len(general):
            apart = set(general.tolist())
            kept = [(i, v) for i, v in zip(positions, values) if i not in apart]
            positions, values = [i for i, _ in kept], [v for _, v in kept]
            for i in apart:
                self._update(i, snap, None if codes is None else Quality(int(codes[i])))
        try:
            shown = self.settle(positions, values) if positions else []
        except Exception:  # no log: settled one by one below, each fault reported with its element
            shown = None
        models, puts, repaint = self.models, self.puts, []
        for k, i in enumerate(positions):
            try:
                if puts[i](models[i].settle(values[k]) if shown is None else shown[k]):
                    repaint.append(i)
            except Exception as e:  # no log: the view's fault handler logs and shows it
                self._failed(i, e)
        return repaint

    def _judge(self, readings: Readings) -> np.ndarray:
        qmap = readings.quality_map
        if self.judged_by is not qmap:  # the station's program (and its NREADs) changed
            self.judged_by, self.operands = qmap, qmap.operands(self.sources)
            self.links = [i for i, (a, n) in enumerate(self.sources) if n == 0 and a in qmap.link_bits]
        assert self.operands is not None
        codes = readings.judge(self.operands)
        for i in self.links:
            codes[i] = readings.address(*self.sources[i])
        return codes

    def _update(self, i: int, snap: Snapshot, quality: Quality | None) -> None:
        model = self.models[i]
        self.bank.forget(i)
        try:
            if model.update(snap, quality):
                self.syncs[i]()
        except Exception as e:  # no log: the view's fault handler logs and shows it
            self._failed(i, e)
        self.marked[i] = bool(model.quality)

    def _failed(self, i: int, error: Exception) -> None:
        """Reported and marked stale, as a failed update is; its value is taken again next time."""
        self.fault(self.models[i], error)
        self.bank.forget(i)
        self.syncs[i]()
