"""The function registry: every FON function registered once by number and mnemonic.

The parameter kinds let the STL parser check a FON at load time, so a constant where an address is
needed or a BCD constant with a digit 8 is an error with a line number, not a wrong value at run
time. Kinds follow the manual's table: M address, O octal, D decimal, B BCD (up to 4 digits).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, Protocol

if TYPE_CHECKING:
    from netplc.memory import Memory
    from netplc.records import RecordSink

ParamKind = Literal["M", "O", "D", "B"]

# Codes the manual defines (section 4.0 of the spec digest); anything else is a load error.
DEFINED_CODES: frozenset[int] = frozenset(
    [*range(0, 5), *range(7, 15), 18, 19, 20, 21, 22, 23, 36, 37, 38, 39, 41, 50, 51, 53, 54, 55, 56,
     57, 58, 63, 64, 65, 66, 68, 69, 70, 71, 74, 75, 76, 81, 82, 83, 84, 90, 91, 92, 93, 94, 95, 98,
     99, *range(300, 317)]
)


class NetLink(Protocol):
    """What NODE/NREAD/NWRITE need from the exchange (netplc/exchange.py implements it)."""

    def request_read(self, key: int, node: int, remote: int, local: int, length: int) -> bool:
        """Queue a block read (once per key while one is in flight); return the node's link state."""
        ...

    def request_write(self, key: int, node: int, remote: int, payload: bytes) -> bool:
        """Queue a block write (once per key while one is in flight); return the node's link state."""
        ...


class FonContext(Protocol):
    """What a function sees of the engine while it runs (the Engine class satisfies it)."""

    mem: Memory
    scan_counter: int  # number of the scan being executed, 0-based
    now: float  # engine clock, monotonic seconds
    dt: float  # seconds since the previous scan
    sink: RecordSink
    exchange: NetLink | None
    node: int  # current node selected by NODE

    def wall_time(self) -> float: ...


@dataclass(slots=True)
class Fon:
    """One FON instruction as the engine runs it; `state` is the instruction's private scratch."""

    c: int
    f: int
    s: int | None
    d: int | None
    r: int | None
    index: int = 0  # instruction index in the program
    line: int = 0
    state: dict = field(default_factory=dict)


Run = Callable[[FonContext, Fon], None]
# Python source lines doing what `run` does for this instruction, for the compiled engine to put in
# line (netplc/compiler.py): they see the bit array as `b`, the data array as `d` and as 16-bit words
# `w`, the engine as `eng`, may use the locals _t _v _x _y, and run only when RES is 1 (after bit C
# is set). None: call `run` instead.
Inline = Callable[[Fon], list[str] | None]


@dataclass(frozen=True, slots=True)
class FunctionSpec:
    number: int
    mnemonic: str
    s: ParamKind | None
    d: ParamKind | None
    r: ParamKind | None
    run: Run
    hardware: bool = False  # a CPU-165 module function: sets FErr1 on this platform
    inline: Inline | None = None
    limits: tuple[tuple[str, int, int], ...] = ()  # (key, lo, hi) of a constant narrower than a word

    def kinds(self) -> dict[str, ParamKind | None]:
        return {"S": self.s, "D": self.d, "R": self.r}

    def bounds(self, key: str) -> tuple[int, int]:
        """The range a constant parameter takes (the manual's; a 16-bit word unless it says less)."""
        return next(((lo, hi) for k, lo, hi in self.limits if k == key), (0, 0xFFFF))


REGISTRY: dict[int, FunctionSpec] = {}
BY_NAME: dict[str, FunctionSpec] = {}


def register(
    number: int,
    mnemonic: str,
    s: ParamKind | None = None,
    d: ParamKind | None = None,
    r: ParamKind | None = None,
    *,
    hardware: bool = False,
    inline: Inline | None = None,
    limits: tuple[tuple[str, int, int], ...] = (),
) -> Callable[[Run], Run]:
    """Decorator: register `run` as function `number` / `mnemonic` with its parameter kinds."""

    def deco(run: Run) -> Run:
        if number in REGISTRY or mnemonic in BY_NAME:
            raise RuntimeError(f"function {number} {mnemonic} registered twice")
        spec = FunctionSpec(number, mnemonic, s, d, r, run, hardware, inline, limits)
        REGISTRY[number] = spec
        BY_NAME[mnemonic] = spec
        return run

    return deco


def lookup(key: int | str) -> FunctionSpec | None:
    """Find a function by number or mnemonic (case-insensitive)."""
    _load_all()
    if isinstance(key, int):
        return REGISTRY.get(key)
    return BY_NAME.get(key.upper())


_loaded = False


def _load_all() -> None:
    """Import every function module once so that their @register calls have run. Done only when
    every import succeeded: a module that fails to import raises here, at every lookup, instead of
    leaving a registry that answers "unknown function" for all that module held."""
    global _loaded
    if _loaded:
        return
    import importlib
    import pkgutil

    import netplc.functions as pkg

    for info in pkgutil.iter_modules(pkg.__path__):
        if info.name != "registry":
            importlib.import_module(f"netplc.functions.{info.name}")
    _loaded = True
