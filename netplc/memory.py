"""NetPlc memory: 2048 I/O bits and 16 KB of data in eight banks, plus immutable snapshots.

I/O bits are kept one per element of a Python list because contacts and coils are by far the most
frequent operations: the compiled program touches them with a plain index, and indexing a list
costs about half what indexing a bytearray does in CPython 3.11. An element is 0/1 or False/True
(the compiled program stores comparison results as they are); the read API always gives 0 or 1.
A snapshot keeps the bits as a tuple: copying the list into one costs a third of converting it to
bytes, and the engine publishes a snapshot after every scan. Byte and word operands
below 04000 are assembled from 8 or 16 consecutive bits (bit A+k is bit k of the value).
Words are little-endian; 32-bit values are low word first (docs/architecture.md section 3).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from netplc.address import (
    DATA_SIZE,
    HMI_DATA_BIT_BASE,
    IO_BITS,
    AddressError,
    BitRef,
    check_operand,
    data_index,
    fmt_octal,
)

if TYPE_CHECKING:
    from netplc.forcing import Force


class MemoryView:
    """Read access shared by the live memory and its snapshots."""

    bits: tuple[int, ...] | list[int]  # 0/1 or False/True
    data: bytes | bytearray

    def get_bit(self, addr: int) -> int:
        if not 0 <= addr < IO_BITS:
            raise AddressError("addr not io bit", addr=fmt_octal(addr))
        return 1 if self.bits[addr] else 0  # the compiled program may store True/False

    def read(self, addr: int, n: int) -> bytes:
        """`n` bytes starting at operand address `addr` (I/O bits or data)."""
        check_operand(addr, n)
        if addr < IO_BITS:
            bits = self.bits
            out = bytearray(n)
            for i in range(n):
                base = addr + 8 * i
                v = 0
                for k in range(8):
                    v |= bits[base + k] << k
                out[i] = v
            return bytes(out)
        i = data_index(addr)
        return bytes(self.data[i : i + n])

    def get_byte(self, addr: int) -> int:
        if addr >= IO_BITS:
            return self.data[data_index(addr)]
        return self.read(addr, 1)[0]

    def get_word(self, addr: int) -> int:
        if addr >= IO_BITS:
            check_operand(addr, 2)
            i = data_index(addr)
            d = self.data
            return d[i] | d[i + 1] << 8
        return int.from_bytes(self.read(addr, 2), "little")

    def get_dword(self, addr: int) -> int:
        return int.from_bytes(self.read(addr, 4), "little")

    def get_hmi_bit(self, ref: BitRef | int) -> int:
        hmi = ref.hmi if isinstance(ref, BitRef) else ref
        if hmi < IO_BITS:
            return 1 if self.bits[hmi] else 0
        if hmi < HMI_DATA_BIT_BASE:
            raise AddressError("addr not hmi bit", addr=fmt_octal(hmi))
        return (self.data[data_index(hmi >> 3)] >> (hmi & 7)) & 1


class Memory(MemoryView):
    """The live memory. Only the engine thread writes it (docs/architecture.md section 1)."""

    def __init__(self) -> None:
        self.bits: list[int] = [0] * IO_BITS
        self.data = bytearray(DATA_SIZE)

    def set_bit(self, addr: int, value: int) -> None:
        if not 0 <= addr < IO_BITS:
            raise AddressError("addr not io bit", addr=fmt_octal(addr))
        self.bits[addr] = 1 if value else 0

    def write(self, addr: int, payload: bytes | bytearray) -> None:
        """Write bytes at operand address `addr` (I/O bits or data)."""
        n = len(payload)
        check_operand(addr, n)
        if addr < IO_BITS:
            bits = self.bits
            for i, v in enumerate(payload):
                base = addr + 8 * i
                for k in range(8):
                    bits[base + k] = (v >> k) & 1
            return
        i = data_index(addr)
        self.data[i : i + n] = payload

    def set_byte(self, addr: int, value: int) -> None:
        if addr >= IO_BITS:
            self.data[data_index(addr)] = value & 0xFF
        else:
            self.write(addr, bytes((value & 0xFF,)))

    def set_word(self, addr: int, value: int) -> None:
        if addr >= IO_BITS:
            check_operand(addr, 2)
            i = data_index(addr)
            self.data[i] = value & 0xFF
            self.data[i + 1] = (value >> 8) & 0xFF
        else:
            self.write(addr, (value & 0xFFFF).to_bytes(2, "little"))

    def set_dword(self, addr: int, value: int) -> None:
        self.write(addr, (value & 0xFFFFFFFF).to_bytes(4, "little"))

    def set_hmi_bit(self, ref: BitRef | int, value: int) -> None:
        hmi = ref.hmi if isinstance(ref, BitRef) else ref
        if hmi < IO_BITS:
            self.bits[hmi] = 1 if value else 0
            return
        if hmi < HMI_DATA_BIT_BASE:
            raise AddressError("addr not hmi bit", addr=fmt_octal(hmi))
        i = data_index(hmi >> 3)
        mask = 1 << (hmi & 7)
        self.data[i] = (self.data[i] | mask) if value else (self.data[i] & ~mask & 0xFF)

    def snapshot(self, scan: int = 0, time: float = 0.0, wall: float = 0.0, state: str = "",
                 forces: tuple[Force, ...] = ()) -> Snapshot:
        return Snapshot(tuple(self.bits), bytes(self.data), scan, time, wall, state, forces)

    def load(self, view: MemoryView) -> None:
        """Replace the whole contents (used by retentive restore and tests)."""
        self.bits[:] = view.bits
        self.data[:] = view.data


@dataclass(frozen=True, slots=True)
class Snapshot(MemoryView):
    """The memory as it was after one scan: what HMI, registrar and Modbus reads see."""

    bits: tuple[int, ...]  # 0/1 or False/True: read them through get_bit, or by truth
    data: bytes
    scan: int = 0  # scan counter after the scan that produced it
    time: float = 0.0  # engine clock (monotonic seconds)
    wall: float = 0.0  # wall clock, seconds since the epoch
    state: str = ""  # engine run state
    forces: tuple[Force, ...] = ()  # what was forced in that scan (netplc/forcing.py): "F: n forced"

    @classmethod
    def empty(cls) -> Snapshot:
        return cls((0,) * IO_BITS, bytes(DATA_SIZE))
