"""Sync generators (manual 2.4.3, Fig. 2.4.3): one-tick pulses counted on the NetPlc scan counter.

A snapshot carrying scan counter S was published after S scans; the output written now is applied
at the start of scan number S (counting from 0), so the program of that scan sees
`S mod Period == Phase`. With pairs (5,0)/(10,1) and select bit 0, the output is 1 in scans
0, 5, 10, ...; with the select bit 1, in scans 1, 11, 21, ...
Generators are the only elements that write without an operator: the runtime evaluates them from
every snapshot on the engine thread and they write through its unjournaled `Effects.set_bit`, once
per new scan (a snapshot seen twice writes nothing more), so no pulse depends on a view.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from app.scada.words import Phrase, phrase
from hmi_forms.elements import props as p
from hmi_forms.elements.base import Element
from netplc.address import BitRef
from netplc.memory import Snapshot

PERIOD = p.integer(1, 1_000_000)
PHASE = p.integer(0, 999_999)


@dataclass(eq=False)
class SyncGenerator(Element):
    TYPE = "SyncGenerator"

    InAddr: BitRef | None = field(default=None, metadata=p.prop(p.bit, alias="Address"))
    OutAddr: BitRef | None = field(default=None, metadata=p.prop(p.bit, required=True))
    Period0: int = field(default=1, metadata=p.prop(PERIOD))
    Phase0: int = field(default=0, metadata=p.prop(PHASE))
    Period1: int = field(default=1, metadata=p.prop(PERIOD))
    Phase1: int = field(default=0, metadata=p.prop(PHASE))

    pair: int = field(default=0, init=False)
    output: int = field(default=0, init=False)
    enabled: bool = field(default=True, init=False)
    last_scan: int = field(default=-1, init=False)

    def check(self, ctx: p.Context) -> list[tuple[str, Phrase]]:
        pairs = (("Phase0", self.Period0, self.Phase0), ("Phase1", self.Period1, self.Phase1))
        return [(name, phrase("form phase", phase=phase, period=period))
                for name, period, phase in pairs if phase >= period]

    @property
    def period_phase(self) -> tuple[int, int]:
        return (self.Period1, self.Phase1) if self.pair else (self.Period0, self.Phase0)

    @property
    def acts(self) -> bool:
        return True

    def is_enabled(self, snap: Snapshot) -> bool:
        return True

    def refresh(self, snap: Snapshot) -> bool:
        if snap.scan == self.last_scan:
            return False
        self.last_scan = snap.scan
        pair = snap.get_hmi_bit(self.InAddr) if self.InAddr is not None else 0
        enabled = self.is_enabled(snap)
        changed = (pair, enabled) != (self.pair, self.enabled)
        self.pair, self.enabled = pair, enabled
        period, phase = self.period_phase
        out = 1 if enabled and snap.scan % period == phase else 0
        if self.effects is not None and self.OutAddr is not None:
            self.effects.set_bit(self.OutAddr.hmi, out)
        changed = changed or out != self.output
        self.output = out
        return changed


@dataclass(eq=False)
class SyncTimer(SyncGenerator):
    """The generator enabled by the bit Ainput; its output is 0 while disabled."""

    TYPE = "SyncTimer"

    Ainput: BitRef | None = field(default=None, metadata=p.prop(p.bit, required=True))

    def is_enabled(self, snap: Snapshot) -> bool:
        return self.Ainput is not None and bool(snap.get_hmi_bit(self.Ainput))
