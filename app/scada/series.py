"""The quality of the archive's data series, so that a plot never draws a frozen value as live.

NSTORE (the program) and a form's RegData write data records, which have no quality column: the
record's `text` holds the quality word when the value is not good (NULL when it is). Two cases
would still leave a series flat where nothing was known: NSTORE does not run while NetPlc is
stopped, and RegData writes only a changed value, so a value frozen by a node that is down writes
nothing. Therefore, when a series' quality turns from good (or forced) to one that holds it (bad
or initial, `Quality.held`), one record marks it at once: no value, the quality word as its text.
The readers (registrar/query.py, registrar/plant/query.py) break the series' line at every record
whose text is such a word (`GAP_WORDS`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

from app.scada.quality import LinkView, Quality, QualityMap, code_flags
from app.scada.tag import Tag, TagType
from netplc.address import fmt_octal, parse_octal
from netplc.lazy import lazy
from netplc.memory import MemoryView
from netplc.program import Program
from netplc.records import Record

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it

NSTORE = 304
GAP_WORDS = tuple(q.word for q in Quality if q.held)  # a data record with one of these is no point


def nstore_keys(program: Program) -> dict[str, set[tuple[int | None, int | None]]]:
    """The series the program's NSTOREs write: the source of their records (the octal address
    of the word stored) -> their (group, type)."""
    keys: dict[str, set[tuple[int | None, int | None]]] = {}
    for ins in program.instrs:
        if ins.op == "FON" and ins.n == NSTORE and ins.s is not None:
            keys.setdefault(fmt_octal(ins.s), set()).add((ins.d, ins.r))
    return keys


class SeriesQuality:
    """Which operands each archived series reads (the program's NSTOREs, the forms' RegData
    elements by name), worked out once; per scan, each series' quality and the records that mark
    a series turning held."""

    def __init__(self, program: Program, regdata: Mapping[str, Sequence[tuple[int, int]]]) -> None:
        """`regdata`: a RegData element's name (the `source` of its records) -> its operands as
        (address, bytes), bytes 0 for one HMI bit (`Element.sources()`)."""
        self.keys = nstore_keys(program)  # source -> (grp, type); RegData's below
        operands: dict[str, Sequence[tuple[int, int]]] = {
            source: ((parse_octal(source), 2),) for source in self.keys}
        for name, sources in regdata.items():
            if sources:
                operands[name] = sources
                self.keys.setdefault(name, set()).add((None, None))
        self.sources = list(operands)
        self._index = {s: i for i, s in enumerate(self.sources)}
        tags, owner = [], []
        for i, source in enumerate(self.sources):
            for addr, nbytes in operands[source]:
                tags.append(Tag(f"S{len(tags)}", addr, TagType.BIT if nbytes == 0 else TagType.WORD))
                owner.append(i)
        self.map = QualityMap(program, tags)
        self._owner = np.array(owner, dtype=np.intp)
        # as of the last scan; before the first nothing is known, so a start marks nothing
        self.codes = np.full(len(self.sources), Quality.INITIAL, dtype=np.int8)

    def evaluate(self, view: MemoryView, links: LinkView, wall: float) -> list[Record]:
        """Each series' quality in this scan; a record for each series that turned held."""
        per_operand = self.map.evaluate(view, links)
        codes = np.zeros(len(self.sources), dtype=np.int8)
        np.maximum.at(codes, self._owner, per_operand)  # the worst of the series' operands
        held = code_flags()[1]
        turned = np.flatnonzero(held[codes] & ~held[self.codes]).tolist()
        self.codes = codes
        out = []
        for i in turned:
            source, word = self.sources[i], Quality(int(codes[i])).word
            for grp, typ in sorted(self.keys[source], key=str):
                out.append(Record(wall, "data", grp=grp, type=typ, source=source, value=None, text=word))
        return out

    def stamp(self, record: Record) -> Record:
        """A data record of a series whose value is not good, with the quality word as its text."""
        i = self._index.get(record.source or "")
        if i is None or record.text is not None:
            return record
        quality = Quality(int(self.codes[i]))
        return record if quality is Quality.GOOD else replace(record, text=quality.word)
