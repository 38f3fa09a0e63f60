"""A tag: a named piece of NetPlc memory with its type, unit and hardware/physical conversion.

The conversion is the manual's (section 2.4.1, docs/architecture.md section 9), and it is the only
one: forms, journal, viewer and CSV convert through `Scaling`; a 32-bit tag's bytes are read and
written in its `byte_order` by `raw`, `encode` and `TagReader` alone, so every reader and writer
follows it. `Scaling.to_phy` is written so that it also runs element-wise on numpy arrays, which
is how `TagReader` converts thousands of tags in one step with the very same arithmetic (and so
the very same results) as a single tag.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from operator import itemgetter

from netplc.address import (
    IO_BITS,
    check_operand,
    data_index,
    parse_hmi_bit,
)
from netplc.functions._util import bcd_to_bin
from netplc.lazy import lazy
from netplc.memory import MemoryView

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it


@dataclass(frozen=True, slots=True)
class Scaling:
    """Linear hardware <-> physical conversion (docs/architecture.md section 9)."""

    AppMin: float
    AppMax: float
    PhyMin: float
    PhyMax: float

    def to_phy(self, hw: float) -> float:
        return self.PhyMin + (hw - self.AppMin) * (self.PhyMax - self.PhyMin) / (self.AppMax - self.AppMin)

    def to_hw(self, phy: float, limits: tuple[float, float] = (0, 0xFFFF), whole: bool = True) -> float:
        """The inverse, clamped to the hardware range and to `limits` (by default an unsigned word),
        and rounded when the hardware holds whole numbers."""
        hw = self.AppMin + (phy - self.PhyMin) * (self.AppMax - self.AppMin) / (self.PhyMax - self.PhyMin)
        lo, hi = sorted((self.AppMin, self.AppMax))
        hw = min(max(hw, lo, limits[0]), hi, limits[1])
        return min(max(round(hw), limits[0]), limits[1]) if whole else hw

    @property
    def phy_range(self) -> tuple[float, float]:
        lo, hi = sorted((self.PhyMin, self.PhyMax))
        return lo, hi

    def fraction(self, phy: float) -> float:
        """Position of `phy` on the scale PhyMin..PhyMax, clamped to 0..1 (for pointers and bars)."""
        f = (phy - self.PhyMin) / (self.PhyMax - self.PhyMin)
        return min(max(f, 0.0), 1.0)


class TagType(StrEnum):
    BIT = "bit"
    WORD = "word"  # unsigned 16
    INT16 = "int16"
    BCD = "bcd"  # 4 BCD digits in a word, 0-9999
    INT32 = "int32"  # two words, in the tag's byte order (NetPlc's: low word first)
    FLOAT32 = "float32"  # IEEE single over two words, in the tag's byte order


# The byte order of a 32-bit value over two registers, as Modbus tools name it (mbpoll, Kepware,
# Modbus Poll): the value's bytes numbered 1 (most significant) to 4, in the order they travel,
# the first register's high byte first. 1234 is big-endian (ABCD), 4321 little-endian (DCBA),
# 2143 big-endian with the bytes of each word swapped (BADC), 3412 the words swapped (CDAB).
BYTE_ORDERS = ("1234", "4321", "2143", "3412")
NETPLC_ORDER = "3412"  # NetPlc's own (docs/architecture.md section 3): low word first, a word's
# low byte first in memory and its high byte first in a register: CDAB on the wire


def _memory_order(order: str) -> tuple[int, int, int, int]:
    """Which byte of NetPlc memory holds each byte of the value, most significant first. A register
    carries its word high byte first and memory keeps it low byte first: the byte that travels
    at position i is memory byte i ^ 1 (NREAD/NWRITE and our server move the words as they are)."""
    where = [0, 0, 0, 0]
    for position, digit in enumerate(order):
        where[int(digit) - 1] = position ^ 1
    return tuple(where)  # type: ignore[return-value]


MEMORY_ORDER = {order: _memory_order(order) for order in BYTE_ORDERS}
WIDE = (TagType.INT32, TagType.FLOAT32)  # the types a byte order applies to


# bytes in memory, and the lowest and highest hardware value
SIZES = {TagType.BIT: 0, TagType.WORD: 2, TagType.INT16: 2, TagType.BCD: 2, TagType.INT32: 4,
         TagType.FLOAT32: 4}
LIMITS: dict[TagType, tuple[float, float]] = {
    TagType.BIT: (0, 1), TagType.WORD: (0, 0xFFFF), TagType.INT16: (-0x8000, 0x7FFF),
    TagType.BCD: (0, 9999), TagType.INT32: (-(2**31), 2**31 - 1),
    TagType.FLOAT32: (-3.4028234663852886e38, 3.4028234663852886e38),
}


def span(addr: int, nbytes: int) -> tuple[int, int]:
    """[first, last) of an operand of `nbytes` bytes in the HMI bit space (I/O bit n = n, data bit =
    byte*8+bit): one space in which tags, NREAD blocks and forced addresses can overlap."""
    return (addr, addr + 8 * nbytes) if addr < IO_BITS else (8 * addr, 8 * (addr + nbytes))


def check_address(addr: int, kind: TagType) -> None:
    """AddressError if `addr` cannot hold a value of `kind` (a bit: an HMI bit address)."""
    if kind is TagType.BIT:
        parse_hmi_bit(addr)
    else:
        check_operand(addr, SIZES[kind])


@dataclass(frozen=True)
class Tag:
    name: str
    address: int  # an HMI bit address for a bit, else the operand address of the first byte
    type: TagType = TagType.WORD
    unit: str = ""
    scaling: Scaling | None = None  # None: the physical value is the hardware value
    decimals: int = 0
    description: str = ""
    byte_order: str = NETPLC_ORDER  # of a 32-bit tag (BYTE_ORDERS): how the device placed it

    @property
    def limits(self) -> tuple[float, float]:
        """The hardware values the type can hold."""
        return LIMITS[self.type]

    @property
    def phy_limits(self) -> tuple[float, float]:
        """The physical values the tag can take: its type's range through the conversion."""
        lo, hi = self.limits
        if self.scaling is None:
            return lo, hi
        a, b = self.scaling.to_phy(lo), self.scaling.to_phy(hi)
        return min(a, b), max(a, b)

    def raw(self, view: MemoryView) -> float:
        """The hardware value; NaN for a BCD word with a digit above 9 (it is not a number)."""
        kind = self.type
        if kind is TagType.BIT:
            return view.get_hmi_bit(self.address)
        if kind is TagType.WORD:
            return view.get_word(self.address)
        if kind is TagType.INT16:
            w = view.get_word(self.address)
            return w - 0x10000 if w & 0x8000 else w
        if kind is TagType.BCD:
            v = bcd_to_bin(view.get_word(self.address))
            return float("nan") if v is None else v
        data = view.read(self.address, 4)
        value = bytes(data[i] for i in MEMORY_ORDER[self.byte_order])  # most significant byte first
        if kind is TagType.INT32:
            return int.from_bytes(value, "big", signed=True)
        return struct.unpack(">f", value)[0]

    def value(self, view: MemoryView) -> float:
        """The physical value."""
        raw = self.raw(view)
        return raw if self.scaling is None else self.scaling.to_phy(raw)

    def word_value(self, word: int) -> float:
        """The physical value of a one-word tag whose word in memory is `word` (NaN: not BCD)."""
        kind = self.type
        if kind is TagType.INT16:
            raw: float = word - 0x10000 if word & 0x8000 else word
        elif kind is TagType.BCD:
            v = bcd_to_bin(word)
            raw = float("nan") if v is None else v
        else:
            raw = word
        return raw if self.scaling is None else self.scaling.to_phy(raw)

    def change(self, old_word: int, new_word: int) -> str:
        """An operator's write as the journal shows it: "0.0 -> 130.0 °C"."""
        return f"{self.word_value(old_word):.{self.decimals}f} -> {self.format(self.word_value(new_word))}"

    def to_raw(self, phy: float) -> float:
        """The hardware value for a physical one: rounded for whole types, clamped to the range."""
        whole = self.type is not TagType.FLOAT32
        if self.scaling is None:
            lo, hi = self.limits
            v = min(max(phy, lo), hi)
            return min(max(round(v), lo), hi) if whole else v
        return self.scaling.to_hw(phy, self.limits, whole)

    def encode(self, raw: float) -> bytes:
        """The bytes of a hardware value as they go into memory (not for bits), a 32-bit one in the
        tag's byte order."""
        kind = self.type
        if kind in WIDE:
            value = struct.pack(">f", raw) if kind is TagType.FLOAT32 else \
                (int(raw) & 0xFFFFFFFF).to_bytes(4, "big")
            data = bytearray(4)
            for byte, i in zip(value, MEMORY_ORDER[self.byte_order], strict=True):
                data[i] = byte
            return bytes(data)
        v = int(raw)
        if kind is TagType.BCD:
            v = (v // 1000) << 12 | (v // 100 % 10) << 8 | (v // 10 % 10) << 4 | v % 10
        return (v & 0xFFFF).to_bytes(2, "little")

    def format(self, phy: float) -> str:
        """The physical value as an operator reads it: its decimals and unit."""
        text = f"{phy:.{self.decimals}f}"
        return f"{text} {self.unit}" if self.unit else text

    @property
    def operand(self) -> tuple[int, int]:
        """(address, bytes), bytes 0 for a bit: the tag as an element's `sources()` names an operand,
        for the readers that judge or watch operands (quality, a console's watched memory)."""
        return self.address, SIZES[self.type]

    def footprint(self) -> tuple[int, int]:
        """[first, last) in the HMI bit space (I/O bit n = n, data bit = byte*8+bit) that the tag
        occupies: what `quality.py` overlaps with the blocks NREADs fill."""
        if self.type is TagType.BIT:
            return self.address, self.address + 1
        return span(self.address, SIZES[self.type])


class TagReader:
    """The physical values of many tags at once, in a numpy array in the order of `tags`.

    Data-memory words, double words and bits are gathered by numpy, I/O bits by one C-level
    itemgetter; only words made of I/O bits (rare) are read one by one. Per scan this costs tens
    of microseconds for thousands of tags.
    """

    def __init__(self, tags: Sequence[Tag]) -> None:
        self.tags = list(tags)
        self._groups: list[tuple[np.ndarray, np.ndarray, TagType]] = []  # positions, byte indexes, type
        self._singles: list[tuple[int, Tag]] = []
        io_bits: list[tuple[int, int]] = []
        data_bits: list[tuple[int, int, int]] = []
        by_type: dict[tuple[TagType, str], list[tuple[int, int]]] = {}
        for pos, tag in enumerate(self.tags):
            if tag.type is TagType.BIT:
                if tag.address < IO_BITS:
                    io_bits.append((pos, tag.address))
                else:
                    data_bits.append((pos, data_index(tag.address >> 3), tag.address & 7))
            elif tag.address < IO_BITS:
                self._singles.append((pos, tag))
            else:
                order = tag.byte_order if tag.type in WIDE else ""
                by_type.setdefault((tag.type, order), []).append((pos, data_index(tag.address)))
        for (kind, order), items in by_type.items():
            positions = np.array([p for p, _ in items], dtype=np.intp)
            first = np.array([i for _, i in items], dtype=np.intp)
            # a 32-bit tag's bytes gathered most significant first, whatever order memory holds them in
            offsets = np.array(MEMORY_ORDER[order]) if order else np.arange(SIZES[kind])
            self._groups.append((positions, first[:, None] + offsets, kind))
        self._io_pos = np.array([p for p, _ in io_bits], dtype=np.intp)
        self._io_get = itemgetter(*(a for _, a in io_bits), 0)  # always a tuple, one item too many
        self._bit_pos = np.array([p for p, _, _ in data_bits], dtype=np.intp)
        self._bit_byte = np.array([i for _, i, _ in data_bits], dtype=np.intp)
        self._bit_shift = np.array([k for _, _, k in data_bits], dtype=np.uint8)
        nan = float("nan")
        scalings = [t.scaling or Scaling(nan, nan, nan, nan) for t in self.tags]
        self._scaled = np.array([t.scaling is not None for t in self.tags], dtype=bool)
        self._scaling = Scaling(*(np.array([getattr(s, k) for s in scalings], dtype=np.float64)
                                  for k in ("AppMin", "AppMax", "PhyMin", "PhyMax")))

    def raw(self, view: MemoryView) -> np.ndarray:
        out = np.empty(len(self.tags), dtype=np.float64)
        data = np.frombuffer(view.data, dtype=np.uint8)
        for positions, index, kind in self._groups:
            block = data[index]  # one row of bytes per tag
            if kind is TagType.WORD:
                out[positions] = block.view("<u2")[:, 0]
            elif kind is TagType.INT16:
                out[positions] = block.view("<i2")[:, 0]
            elif kind is TagType.INT32:
                out[positions] = block.view(">i4")[:, 0]
            elif kind is TagType.FLOAT32:
                out[positions] = block.view(">f4")[:, 0]
            else:  # BCD
                hi, lo = block[:, 1], block[:, 0]
                nibbles = np.stack((hi >> 4, hi & 15, lo >> 4, lo & 15), 1)
                values = nibbles.astype(np.float64) @ np.array([1000.0, 100.0, 10.0, 1.0])
                values[(nibbles > 9).any(axis=1)] = np.nan
                out[positions] = values
        if len(self._bit_pos):
            out[self._bit_pos] = (data[self._bit_byte] >> self._bit_shift) & 1
        if len(self._io_pos):
            out[self._io_pos] = np.array(self._io_get(view.bits)[:-1], dtype=bool)
        for pos, tag in self._singles:
            out[pos] = tag.raw(view)
        return out

    def convert(self, raw: np.ndarray) -> np.ndarray:
        """Physical values of the hardware values `raw` (one per tag)."""
        return np.where(self._scaled, self._scaling.to_phy(raw), raw)

    def read(self, view: MemoryView) -> np.ndarray:
        return self.convert(self.raw(view))

