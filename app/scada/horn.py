"""The station's horn: whether an alarm is to be heard, for the workstation's sound and for a real
horn the NetPlc program drives.

ISA-18.2 annunciation: a new alarm of priority 1 or 2 sounds until it is acknowledged or the
sound is silenced; a silence stops what sounds now, and only an alarm that comes after it sounds
again. The state is the station's, worked out on the engine thread from the alarm summary each
time it is rebuilt, so every console and the program agree on it: the workstation plays the sound
file of the highest priority sounding (app/gui/annunciation.py), and `alarm_horn` in station.toml
names an HMI bit the station sets to 1 while anything sounds and to 0 after, for the program to
wire to a horn output. Silence is a command of the command layer (Action.SILENCE), journaled.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from app.scada.alarms import AlarmRow, State
from netplc.memory import Memory

SOUNDING = (1, 2)  # priorities that sound until acknowledged or silenced


@dataclass
class Horn:
    bit: int | None = None  # the HMI bit address the program reads; None: no horn output
    silenced_at: float = 0.0  # wall time of the last silence
    priority: int | None = None  # the highest priority sounding now; None: silent

    @property
    def sounding(self) -> bool:
        return self.priority is not None

    def update(self, rows: Sequence[AlarmRow]) -> bool:
        """Follow the summary; True when what sounds changed."""
        now = min((r.priority for r in rows if r.state is State.UNACK and r.priority in SOUNDING
                   and r.since > self.silenced_at), default=None)
        changed = now != self.priority
        self.priority = now
        return changed

    def silence(self, now: float) -> None:
        self.silenced_at = now
        self.priority = None

    def write(self, mem: Memory) -> None:
        """Set the horn bit to what sounds (the engine runs it between two scans)."""
        if self.bit is not None:
            mem.set_hmi_bit(self.bit, 1 if self.sounding else 0)


class AlarmSource(Protocol):
    """An alarm system as the alarm views read it (the summary, the banner, the sound): its rows in
    the summary's order, their `version`, and its horn. `silence(now)` is where the command
    layer's Silence lands: the station's own alarm system on its engine thread
    (app/scada/station.py), a remote console's copy of the station's alarms once the station
    answered the console's Silence (app/gui/console/source.py), so that the console's sound stops
    at once as the station's does. No view silences a horn itself."""

    version: int
    summary: Sequence[AlarmRow]
    horn: Horn

    def silence(self, now: float) -> None: ...
