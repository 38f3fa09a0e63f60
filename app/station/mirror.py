"""What the primary of a hot-standby pair sends its standby after every scan, and how the standby
puts it into its engine (docs/architecture.md section 11).

The state is the engine's own: NetPlc memory (bits and data, which hold the edge memory too: a
CTR's rising edge is RES 1 while its bit C is 0), the timers' and counters' current values, the
forces, the run state and the scan number, and the alarm states the station keeps beside it
(acknowledged by whom, shelved, out of service: app/scada/alarms.py) with its horn's last silence,
and the scan's records, which the standby keeps until the primary has them on disk.
A frame carries only what changed since the frame before it (memory as runs of the 64-byte
blocks that differ, the alarms whose state changed); the first frame of a link is the whole
state, so a standby that comes late or comes back catches up at once.

Frames on the link: a 4-byte big-endian length, then the version byte, the kind byte and the
payload. A state payload is a 4-byte length of its JSON header, the header, then the memory runs
(4-byte offset, 2-byte length, the bytes) over the image of the 2048 bits (one byte each) and the
16 KB of data.
"""

from __future__ import annotations

import json
import socket
import struct
from dataclasses import dataclass, field
from typing import Any

from netplc.address import DATA_SIZE, IO_BITS, fmt_octal, parse_octal
from netplc.engine import Engine, RunState
from netplc.forcing import Force
from netplc.memory import Memory, Snapshot
from netplc.records import Record

VERSION = 1
# frame kinds (ACK: the standby holds scan n; TAKEN: the standby took over, leading from scan n)
HELLO, STATE, HANDOVER, ACK, TAKEN = 1, 2, 3, 4, 5
BLOCK = 64  # bytes compared at a time for a delta
STRETCH = 2048  # bytes compared first: only a stretch that differs is compared block by block
IMAGE = IO_BITS + DATA_SIZE
MAX_FRAME = IMAGE + (1 << 20)  # a whole state and its header, with room to spare
PENDING_SCANS = 10_000  # scans with records the standby keeps for a primary that has none on disk
_HEAD = struct.Struct(">IBB")
_RUN = struct.Struct(">IH")


class LinkError(ConnectionError):
    """The pair link broke, or the partner sent what is no frame of ours."""


class LinkClosed(LinkError):
    """The partner closed the link: how a link usually ends, said in the station's words."""


def send_frame(sock: socket.socket, kind: int, payload: bytes) -> None:
    sock.sendall(_HEAD.pack(len(payload) + 2, VERSION, kind) + payload)


def read_frame(sock: socket.socket) -> tuple[int, bytes]:
    """The next frame's kind and payload; LinkError when the link ends or speaks otherwise."""
    length, version, kind = _HEAD.unpack(_receive(sock, _HEAD.size))
    if version != VERSION:
        raise LinkError(f"pair link version {version}, this station speaks {VERSION}")
    if not 2 <= length <= MAX_FRAME:
        raise LinkError(f"a pair link frame of {length} bytes")
    return kind, _receive(sock, length - 2)


def _receive(sock: socket.socket, n: int) -> bytes:
    out = bytearray()
    while len(out) < n:
        chunk = sock.recv(n - len(out))
        if not chunk:
            raise LinkClosed("the partner closed the pair link")
        out += chunk
    return bytes(out)


@dataclass(frozen=True)
class Capture:
    """One scan of the primary as its listener took it: cheap on the engine thread (the snapshot
    is immutable, the held values a dict); the delta is made on the link's thread."""

    snapshot: Snapshot
    tim: dict[int, float]
    ctr: dict[int, int]
    stop_code: int
    alarms: dict[str, dict[str, Any]] = field(default_factory=dict)  # changed states, by alarm
    bdseq: int = -1  # the MQTT Sparkplug session's bdSeq (-1: no MQTT)
    silenced: float = 0.0  # the wall time of the horn's last silence (app/scada/horn.py)
    records: tuple[Record, ...] = ()  # the scan's records (with their pid), for the standby to keep
    committed: int = -1  # the last scan whose records the primary has on disk (-1: none yet)


def capture(engine: Engine, snapshot: Snapshot, alarms: dict[str, dict[str, Any]],
            bdseq: int = -1, silenced: float = 0.0, records: tuple[Record, ...] = (),
            committed: int = -1) -> Capture:
    """The scan's state; the timers and counters read only at the coils the program has (all
    2048 of each would cost the scan milliseconds)."""
    tim, ctr = engine.tim_ticks, engine.ctr_values
    tims, ctrs = _coils(engine)
    return Capture(snapshot, {c: tim[c] for c in tims if tim[c]}, {c: ctr[c] for c in ctrs if ctr[c]},
                   engine.stop_code, alarms, bdseq, silenced, records, committed)


_COILS: dict[int, tuple[tuple[int, ...], tuple[int, ...]]] = {}  # by id of the program


def _coils(engine: Engine) -> tuple[tuple[int, ...], tuple[int, ...]]:
    program = engine.program
    found = _COILS.get(id(program))
    if found is None:
        instrs = program.instrs
        found = (tuple(sorted({i.c or 0 for i in instrs if i.op == "TIM"})),
                 tuple(sorted({i.c or 0 for i in instrs if i.op == "CTR"})))
        _COILS.clear()  # one program at a time
        _COILS[id(program)] = found
    return found


def image(snapshot: Snapshot) -> bytes:
    return bytes(snapshot.bits) + snapshot.data


@dataclass
class Encoder:
    """The primary's side: each capture as a frame of what changed since the last one sent."""

    last: bytes | None = None  # the image the standby holds; None: send everything
    _extras: str = ""  # the header fields besides the scan, as last sent

    def frame(self, cap: Capture) -> bytes:
        now = image(cap.snapshot)
        runs = [(0, now)] if self.last is None else _delta(self.last, now)
        header: dict[str, Any] = {"scan": cap.snapshot.scan, "full": self.last is None}
        if cap.alarms:
            header["alarms"] = cap.alarms
        if cap.records:
            header["records"] = [[r.pid, r.ts, r.kind, r.grp, r.type, r.source, r.number, r.value, r.text]
                                 for r in cap.records]
        if cap.committed >= 0:
            header["committed"] = cap.committed
        extras = json.dumps({"state": cap.snapshot.state, "stop_code": cap.stop_code,
                             "tim": cap.tim, "ctr": cap.ctr, "bdseq": cap.bdseq, "silenced": cap.silenced,
                             "forces": [[f.kind, fmt_octal(f.addr), f.value, f.user]
                                        for f in cap.snapshot.forces]})
        if extras != self._extras or self.last is None:
            header["extras"] = extras
            self._extras = extras
        self.last = now
        text = json.dumps(header).encode()
        body = b"".join(_RUN.pack(at, len(run)) + run for at, run in _split(runs))
        return struct.pack(">I", len(text)) + text + body


def _delta(old: bytes, new: bytes) -> list[tuple[int, bytes]]:
    """The changed 64-byte blocks of `new`, adjacent ones merged; 2 KB stretches that are equal
    (most of them, most scans) are passed over by one comparison each."""
    runs: list[tuple[int, bytes]] = []
    start = -1
    for outer in range(0, IMAGE, STRETCH):
        if old[outer : outer + STRETCH] == new[outer : outer + STRETCH]:
            if start >= 0:
                runs.append((start, new[start:outer]))
                start = -1
            continue
        for at in range(outer, outer + STRETCH, BLOCK):
            same = old[at : at + BLOCK] == new[at : at + BLOCK]
            if not same and start < 0:
                start = at
            elif same and start >= 0:
                runs.append((start, new[start:at]))
                start = -1
    if start >= 0:
        runs.append((start, new[start:]))
    return runs


def _split(runs: list[tuple[int, bytes]]) -> list[tuple[int, bytes]]:
    """Runs of at most 65535 bytes (the length field's range)."""
    return [(at + i, run[i : i + 0xFFFF]) for at, run in runs for i in range(0, len(run), 0xFFFF)]


@dataclass
class Mirror:
    """The standby's side: the primary's state as the frames built it up."""

    image: bytearray = field(default_factory=lambda: bytearray(IMAGE))
    scan: int = -1  # the primary's scan of the last frame; -1: no full state yet
    state: str = RunState.RUNNING.value
    stop_code: int = 0
    tim: dict[int, float] = field(default_factory=dict)
    ctr: dict[int, int] = field(default_factory=dict)
    forces: tuple[Force, ...] = ()
    alarms: dict[str, dict[str, Any]] = field(default_factory=dict)  # states not yet put, by alarm
    bdseq: int = -1  # the primary's MQTT Sparkplug bdSeq
    silenced: float = 0.0  # when the primary's horn was last silenced
    # the primary's records of the scans it may not have on disk yet, by scan: what this station
    # archives if it takes over (app/station/pair.py), and the highest pid the primary gave
    pending: list[tuple[int, list[Record]]] = field(default_factory=list)
    last_pid: int = 0

    @property
    def complete(self) -> bool:
        return self.scan >= 0

    def apply(self, payload: bytes) -> None:
        """One state frame; LinkError for a delta before any full state, or a frame that is bad."""
        try:
            (size,) = struct.unpack_from(">I", payload)
            header = json.loads(payload[4 : 4 + size])
            if not header["full"] and not self.complete:
                raise LinkError("a delta before the full state")
            at = 4 + size
            while at < len(payload):
                offset, length = _RUN.unpack_from(payload, at)
                at += _RUN.size
                if offset + length > IMAGE or at + length > len(payload):
                    raise LinkError(f"a memory run {offset}+{length} outside NetPlc memory")
                self.image[offset : offset + length] = payload[at : at + length]
                at += length
            if "extras" in header:
                extras = json.loads(header["extras"])
                self.state, self.stop_code = extras["state"], int(extras["stop_code"])
                self.tim = {int(c): float(v) for c, v in extras["tim"].items()}
                self.ctr = {int(c): int(v) for c, v in extras["ctr"].items()}
                self.bdseq = int(extras.get("bdseq", -1))
                self.silenced = float(extras.get("silenced", 0.0))
                self.forces = tuple(Force(kind, parse_octal(addr), int(value), user)
                                    for kind, addr, value, user in extras["forces"])
            alarms = header.get("alarms", {})
            if not isinstance(alarms, dict):
                raise TypeError("the alarms are no table")
            self.alarms.update(alarms)
            scan = int(header["scan"])
            records = [Record(ts, kind, grp, typ, source, number, value, text, pid)
                       for pid, ts, kind, grp, typ, source, number, value, text in header.get("records", ())]
            if records:
                self.pending.append((scan, records))
                self.last_pid = max(self.last_pid, *(r.pid or 0 for r in records))
            if "committed" in header:
                committed = int(header["committed"])
                self.pending = [(at, held) for at, held in self.pending if at > committed]
            if len(self.pending) > PENDING_SCANS:  # a primary whose disk fails for long: its oldest
                del self.pending[: len(self.pending) - PENDING_SCANS]  # are lost only if it dies too
            self.scan = scan
        except (struct.error, ValueError, KeyError, TypeError) as e:
            raise LinkError(f"a state frame that cannot be read: {e}") from None

    def load_into(self, engine: Engine, mem: Memory) -> None:
        """Make `engine` (on its thread, between two scans) hold the mirrored state."""
        mem.bits[:] = self.image[:IO_BITS]
        mem.data[:] = self.image[IO_BITS:]
        engine.restore_values(self.tim, self.ctr)
        engine.forces.listing = self.forces
        engine.state = _run_state(self.state)
        engine.stop_code = self.stop_code
        engine.scan_counter = self.scan

    def take_pending(self) -> list[Record]:
        """The primary's records that it may not have on disk: this station, taking over, archives
        them (their pids make a copy the old primary committed too one record in the plant)."""
        pending, self.pending = self.pending, []
        return [r for _scan, records in pending for r in records]

    def take_alarms(self) -> dict[str, dict[str, Any]]:
        """The alarm states received since the last call, for the standby's alarm system."""
        alarms, self.alarms = self.alarms, {}
        return alarms


def _run_state(text: str) -> RunState:
    """The run state of a snapshot's state text ("stopped, code 11" included)."""
    return RunState(text.split(",")[0]) if text.split(",")[0] in RunState._value2member_map_ \
        else RunState.STOPPED
