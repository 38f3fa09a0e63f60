"""CPU-165 address spaces: octal text, validation, and HMI bit addresses.

Addresses are octal in every document an engineer reads, so they are parsed and printed in octal
here and nowhere else. The gaps between the eight data banks are invalid, so that a typo in a
program is a load error instead of a silent write into memory that does not exist on a CPU-165.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from netplc.words import WordedError

IO_BITS = 0o4000  # bits 00000-03777 (00000-01777 external, 02000-03777 internal)
BANKS = 8
BANK_SIZE = 0o4000  # 2 KB per bank
DATA_SIZE = BANKS * BANK_SIZE  # 16 KB
MAX_ADDRESS = 0o77777
HMI_DATA_BIT_BASE = 0o40000  # HMI bit address >= this is byte*8 + bit

# Special I/O bits (docs/architecture.md section 3).
GEN_BASE = 0o3750  # 03750-03757 square-wave generators, 0.1 s * 2**k
ALWAYS_ONE = 0o3760
EMERGENCY_STOP = 0o3770
FERR1 = 0o3771
FERR2 = 0o3772
TIMEBASE_LO = 0o3773
TIMEBASE_HI = 0o3774
RETAIN_BITS = range(0o3000, 0o3500)  # retentive I/O bits 03000-03477

# Special data bytes.
RTC_CONTROL = 0o77700  # 0 = clock runs, non-zero = being set
RTC_FIRST = 0o77701  # seconds, minutes, hours, day, month, year, weekday (BCD)
PRESENCE_LIST = 0o77740  # 077740-077777: 00 absent, FF present, byte i = node i
PRESENCE_NODES = 32

# Octal text: `$` and `0o` prefixes optional, then octal digits only (int(t, 8) alone would also take
# `_`, a sign, white space and other scripts' digits). One match instead of a test per character:
# a program's parse reads thousands of addresses.
OCTAL_TEXT = re.compile(r"\$?(?:0[oO])?([0-7]+)")


class AddressError(WordedError):
    """An address that names no memory of a CPU-165 (its text a phrase of netplc/words.py)."""


def parse_octal(text: str) -> int:
    """Parse `04000`, `$04000` or `4000` as octal; raise a ValueError (WordedError) naming the text."""
    m = OCTAL_TEXT.fullmatch(text.strip())
    if m is None:
        raise WordedError("addr not octal", text=text)
    return int(m.group(1), 8)


def fmt_octal(addr: int, width: int = 5) -> str:
    """Format as the documents do: `04000`, `077700`, `02042`."""
    return "0" + format(addr, "o").rjust(width - 1, "0")


def is_io_bit(addr: int) -> bool:
    return 0 <= addr < IO_BITS


def is_data_byte(addr: int) -> bool:
    return IO_BITS <= addr <= MAX_ADDRESS and (addr & 0o7777) >= 0o4000


def data_index(addr: int) -> int:
    """Index of a data byte in the flat 16 KB data array; AddressError for gaps."""
    if not is_data_byte(addr):
        raise AddressError("addr not data", addr=fmt_octal(addr))
    return (addr >> 12) * BANK_SIZE + (addr & 0o3777)


def data_address(index: int) -> int:
    """Inverse of data_index."""
    return (index // BANK_SIZE) * 0o10000 + 0o4000 + index % BANK_SIZE


def check_operand(addr: int, nbytes: int) -> None:
    """Validate an operand of `nbytes` bytes at `addr` (below 04000: 8*nbytes I/O bits)."""
    if 0 <= addr < IO_BITS:
        if addr + 8 * nbytes > IO_BITS:
            raise AddressError("addr past io", addr=fmt_octal(addr), n=nbytes)
        return
    if not is_data_byte(addr):
        raise AddressError("addr not valid", addr=fmt_octal(addr))
    last = addr + nbytes - 1
    if not is_data_byte(last) or (last >> 12) != (addr >> 12):
        raise AddressError("addr past bank", addr=fmt_octal(addr), n=nbytes)


def is_valid_operand(addr: int, nbytes: int) -> bool:
    try:
        check_operand(addr, nbytes)
    except AddressError:
        return False
    return True


@dataclass(frozen=True, slots=True)
class BitRef:
    """A bit named the HMI way: an I/O bit (< 04000) or `byte*8 + bit` (>= 040000)."""

    hmi: int

    @property
    def is_io(self) -> bool:
        return self.hmi < IO_BITS

    @property
    def byte(self) -> int:
        return self.hmi >> 3

    @property
    def bit(self) -> int:
        return self.hmi & 7

    def __str__(self) -> str:
        return fmt_octal(self.hmi, 6 if self.hmi >= HMI_DATA_BIT_BASE else 5)


def parse_hmi_bit(value: int | str) -> BitRef:
    """Parse an HMI bit address (octal text or int); AddressError if it names no bit."""
    addr = parse_octal(value) if isinstance(value, str) else value
    if is_io_bit(addr):
        return BitRef(addr)
    if addr >= HMI_DATA_BIT_BASE and is_data_byte(addr >> 3):
        return BitRef(addr)
    raise AddressError("addr not bit", addr=fmt_octal(addr))
