"""How NetPlc and CPU-165 memory look in Modbus terms (docs/architecture.md section 7); client and
server share it.

Profile `cpu165` (CPU-165 nodes, the simulator, NetPlc's own server): coil n = I/O bit n; holding
register n = data bytes 2n, 2n+1 as one little-endian word, so byte 04000 is register 1024; the
discrete inputs and input registers alias coils and holding registers. Anything else (register
numbers below 1024, the gaps between the data banks, a block running past the end of a bank) is
Modbus exception 2, exactly as a literal address there is a load error in a program.

Profile `modbus` (any other device): the remote address of NREAD/NWRITE is the register or coil
number in the node's `table`; a register carries one little-endian NetPlc word, a coil one bit.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from netplc.address import BANK_SIZE, IO_BITS, MAX_ADDRESS, AddressError, check_operand, fmt_octal
from netplc.memory import MemoryView
from netplc.words import WordedError

Table = Literal["coils", "discrete", "holding", "input"]
TABLES: tuple[Table, ...] = ("coils", "discrete", "holding", "input")
BIT_TABLES: frozenset[str] = frozenset({"coils", "discrete"})
WRITABLE_TABLES: frozenset[str] = frozenset({"coils", "holding"})
PROFILES = ("cpu165", "modbus")

# Modbus application protocol limits per transaction.
MAX_READ_REGISTERS = 125
MAX_WRITE_REGISTERS = 123
MAX_READ_BITS = 2000
MAX_WRITE_BITS = 1968
ADDRESS_SPACE = 0x10000


class MapError(ValueError):
    """An address the map does not cover: Modbus exception 2 on a server, a failed request on a client."""


class BlockError(WordedError, MapError):
    """A block of NREAD/NWRITE a node's map cannot hold (`locate`): a phrase of netplc/words.py, said
    in the station's language where the program is checked against the nodes."""


# --- packing -------------------------------------------------------------------------------------


def words_from_bytes(data: bytes) -> list[int]:
    """Little-endian words of an even-length byte string (a register carries one NetPlc word)."""
    return [data[i] | data[i + 1] << 8 for i in range(0, len(data), 2)]


def bytes_from_words(words: list[int]) -> bytes:
    out = bytearray(2 * len(words))
    for i, w in enumerate(words):
        out[2 * i] = w & 0xFF
        out[2 * i + 1] = (w >> 8) & 0xFF
    return bytes(out)


def bits_from_bytes(data: bytes) -> list[int]:
    """Bit k of byte i is bit 8*i+k, as bytes below 04000 are assembled from I/O bits."""
    return [(b >> k) & 1 for b in data for k in range(8)]


def bytes_from_bits(bits: list[int]) -> bytes:
    out = bytearray((len(bits) + 7) // 8)
    for i, v in enumerate(bits):
        if v:
            out[i >> 3] |= 1 << (i & 7)
    return bytes(out)


# --- server side: serving a memory view with the cpu165 profile ---------------------------------


def _register_bytes(address: int, count: int) -> int:
    """Byte address of `count` registers from `address`; MapError unless they are data memory."""
    first = 2 * address
    if first < IO_BITS:
        raise MapError(f"register {address} is below 1024 (byte 04000): not data memory")
    try:
        check_operand(first, 2 * count)
    except AddressError as e:
        raise MapError(f"registers {address}+{count}: {e}") from None
    return first


def _check_bits(address: int, count: int) -> None:
    if address < 0 or address + count > IO_BITS:
        raise MapError(f"coils {address}+{count}: I/O bits end at 2047 (03777)")


def read_bits(view: MemoryView, address: int, count: int) -> list[int]:
    """Coils / discrete inputs `address`..+count of a NetPlc or CPU-165 memory."""
    _check_bits(address, count)
    return [1 if v else 0 for v in view.bits[address : address + count]]


def register_slice(data: bytes, address: int, count: int) -> bytes:
    """Holding / input registers `address`..+count of a data memory image (a snapshot's `data`) as
    a Modbus answer carries them: the little-endian words at bytes 2*address.. with their two bytes
    swapped, by slicing, with no list of ints (the server's hot path)."""
    first = 2 * address
    last = first + 2 * count - 1
    if first < IO_BITS or (first & 0o7777) < 0o4000 or last >> 12 != first >> 12 or last > MAX_ADDRESS:
        _register_bytes(address, count)  # raises MapError naming the problem
    i = (first >> 12) * BANK_SIZE + (first & 0o3777)
    chunk = data[i : i + 2 * count]
    out = bytearray(2 * count)
    out[0::2] = chunk[1::2]
    out[1::2] = chunk[0::2]
    return bytes(out)


def bits_target(address: int, count: int) -> int:
    """The I/O bit a coil write of `count` coils at `address` starts at (MapError outside)."""
    _check_bits(address, count)
    return address


def registers_target(address: int, count: int) -> int:
    """The data byte a register write of `count` registers at `address` starts at (MapError outside)."""
    return _register_bytes(address, count)


@dataclass(frozen=True, slots=True)
class MemoryWrite:
    """A Modbus write in NetPlc terms: I/O bits from `first` (coils), or data bytes from `first`
    (registers, each the little-endian word of two bytes)."""

    first: int
    bits: list[int] | None = None
    data: bytes = b""

    @property
    def last(self) -> int:
        return self.first + (len(self.bits) if self.bits is not None else len(self.data)) - 1

    def __str__(self) -> str:
        """As the command layer names a write's target: `03770`, `02050:8 bits`, `04000:4`."""
        first = fmt_octal(self.first)
        if self.bits is not None:
            return first if len(self.bits) == 1 else f"{first}:{len(self.bits)} bits"
        return first if len(self.data) == 2 else f"{first}:{len(self.data)}"


def memory_write(table: str, address: int, values: list[int]) -> MemoryWrite:
    """What a write of `values` to `table` at `address` changes (MapError outside the map)."""
    if table == "coils":
        return MemoryWrite(bits_target(address, len(values)), bits=values)
    return MemoryWrite(registers_target(address, len(values)), data=bytes_from_words(values))


# --- client side: where a block of a remote node lives ------------------------------------------


@dataclass(frozen=True, slots=True)
class Block:
    """R bytes of a remote node in Modbus terms: `count` registers/coils from `address` of `table`.

    `skip` is 1 when a cpu165 byte block starts at an odd byte (the first register's low byte is
    not part of it); `length` is the block length in bytes.
    """

    table: Table
    address: int
    count: int
    skip: int
    length: int

    @property
    def bits(self) -> bool:
        return self.table in BIT_TABLES

    @property
    def odd_end(self) -> bool:
        """The last register holds a byte beyond the block (read-modify-write needed to write it)."""
        return not self.bits and (self.skip + self.length) % 2 == 1

    def spans(self, write: bool) -> list[tuple[int, int]]:
        """(address, count) per Modbus transaction, split at the protocol's size limits."""
        if self.bits:
            limit = MAX_WRITE_BITS if write else MAX_READ_BITS
        else:
            limit = MAX_WRITE_REGISTERS if write else MAX_READ_REGISTERS
        return [(a, min(limit, self.address + self.count - a))
                for a in range(self.address, self.address + self.count, limit)]

    def decode(self, values: list[int]) -> bytes:
        """The block's bytes from the values of all its registers/coils."""
        raw = bytes_from_bits(values) if self.bits else bytes_from_words(values)
        return raw[self.skip : self.skip + self.length]

    def decode_wire(self, data: bytes) -> bytes:
        """The block's bytes straight from the answers' data as the wire carries it (registers
        big-endian, coils packed bit 0 first): a byte swap by slicing, no list of ints."""
        if self.bits:
            return data[: self.length]
        raw = bytearray(len(data))
        raw[0::2] = data[1::2]
        raw[1::2] = data[0::2]
        return bytes(raw[self.skip : self.skip + self.length])

    def encode(self, payload: bytes, first: int = 0, last: int = 0) -> list[int]:
        """Register/coil values writing `payload`; `first`/`last` are the edge registers' current
        values, whose bytes outside the block are kept (read-modify-write of an odd edge)."""
        if self.bits:
            return bits_from_bytes(payload)
        raw = bytearray(bytes_from_words([first]) if self.skip else b"")
        raw[self.skip :] = payload
        if self.odd_end:
            raw.append((last >> 8) & 0xFF)
        return words_from_bytes(bytes(raw))


def locate(profile: str, table: str, remote: int, length: int) -> Block:
    """Map `length` bytes at `remote` (NREAD S / NWRITE D) of a node; MapError names the problem."""
    if length < 1:
        raise BlockError("map no bytes", length=length)
    if profile == "cpu165":
        try:
            check_operand(remote, length)
        except AddressError as e:
            raise BlockError("map remote", error=e) from None
        if remote < IO_BITS:
            return Block("coils", remote, 8 * length, 0, length)
        first, end = remote >> 1, (remote + length + 1) >> 1
        return Block("holding", first, end - first, remote & 1, length)
    if profile == "modbus":
        if table not in TABLES:
            raise BlockError("map table", table=table, tables=", ".join(TABLES))
        count = 8 * length if table in BIT_TABLES else (length + 1) // 2
        if remote < 0 or remote + count > ADDRESS_SPACE:
            raise BlockError("map past", table=table, remote=remote, count=count)
        return Block(table, remote, count, 0, length)  # type: ignore[arg-type]
    raise BlockError("map profile", profile=profile, profiles=", ".join(PROFILES))


def describe(profile: str, remote: int) -> str:
    """A remote address as an engineer reads it: octal for CPU-165 memory, decimal for registers."""
    return fmt_octal(remote) if profile == "cpu165" else str(remote)
