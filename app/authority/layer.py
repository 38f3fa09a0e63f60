"""The station's command layer: every action from any seat or protocol, checked, journaled, answered.

A command carries who (`Who`: the user, or the peer where the protocol has none), from where (its
`Source`) and what (the methods below). The layer
- checks the role against the one policy table (`policy.py`), reading the user's role from the
  station's users at each command, so a role changed or a user removed counts at once;
- checks the value where there is a tag (its type, its physical range PhyMin..PhyMax);
- queues the action to the engine thread through the engine's bounded queue of outside actions
  (`Engine.command`), so the scan period holds whatever clients send and memory has one writer;
- journals it once, as the effect's own record naming who and from where (the write, the force,
  the alarm transition), in one wording for every entry point, in the station's language
  (app/scada/words.py: its records and the sentences of its answers);
- answers (`Ticket`, a future of `Answer`) only when the action was applied and its record is
  committed to the archive, or at once with the reason it was refused, which each protocol maps to
  its own code (`Reason`: a Modbus exception, an OPC UA StatusCode, an NCMD refusal, the console's
  message);
- journals refusals throttled: one record per cause per source per minute, carrying the count of
  the refusals it stands for, so a client hammering a refused write cannot flood the journal.

Qt-free: the workstation, `--no-gui`, the publishers and the Modbus server share it.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING

from app.authority.policy import POLICY, ROLE_OF_SOURCE, ROLES, Action, Refusal, Source, needs, rank
from app.authority.users import UserError
from app.scada.alarms import UnknownAlarm
from app.scada.forcing import forcing_tag, unforcing_tag
from app.scada.station import STOPPED_BY_COMMAND
from app.scada.tag import Tag, TagType
from app.scada.words import Words, phrase, words
from netplc.address import EMERGENCY_STOP, IO_BITS, fmt_octal
from netplc.engine import BUSY, JOURNAL_FULL, Engine, RunState
from netplc.forcing import ForceError, Kind, given
from netplc.memory import Memory
from netplc.records import Record, RecordSink

if TYPE_CHECKING:
    from app.scada.station import StationAlarms

logger = logging.getLogger(__name__)

THROTTLE = 60.0  # s: one refusal record per cause per source per this long


class Reason(StrEnum):
    """Why a command ended as it did; each protocol maps it to its own code."""

    APPLIED = "applied"
    DENIED = "denied"  # the role does not allow it (OPC UA BadUserAccessDenied, Modbus 01)
    NOT_WRITABLE = "not writable"  # never writable from there (BadNotWritable, Modbus 02)
    UNKNOWN = "unknown"  # no such tag, alarm or address (BadNodeIdUnknown, Modbus 02)
    TYPE_MISMATCH = "type mismatch"  # a text for a number (BadTypeMismatch, Modbus 03)
    OUT_OF_RANGE = "out of range"  # outside the tag's physical range (BadOutOfRange, Modbus 03)
    INVALID = "invalid"  # a shelving without reason, a force that does not fit (BadInvalidArgument)
    BUSY = "busy"  # the queue of outside actions is full (BadTooManyOperations, Modbus 06)
    JOURNAL_FULL = "journal full"  # the archive cannot take the record (BadResourceUnavailable, 06)
    NOT_RUNNING = "not running"  # the station is not started (BadServerHalted, Modbus 06)
    STANDBY = "standby"  # the standby of a pair: the text names the primary (BadInvalidState, 06)
    FAILED = "failed"  # applying it failed; journaled as a system record (BadInternalError, 04)


@dataclass(frozen=True)
class Answer:
    reason: Reason
    text: str = ""  # the sentence a person reads, "" when applied
    refusal: Refusal | None = None  # for DENIED: the parts, for the console's language

    @property
    def ok(self) -> bool:
        return self.reason is Reason.APPLIED


APPLIED = Answer(Reason.APPLIED)
Ticket = Future  # Future[Answer]: done once applied and committed, or refused


@dataclass(frozen=True)
class Who:
    """Who acts, and from where. `user` is "" for a protocol without users (Modbus, an NCMD) and
    for a console where nobody is logged in and no default user is named; `peer` is the remote
    address of a remote writer."""

    user: str
    source: Source
    peer: str = ""

    @property
    def name(self) -> str:
        """How the journal names it: the user alone at the workstation, the protocol with its user
        and peer otherwise (`opcua:alice@10.0.0.5:51234`, `modbus 127.0.0.1:40686`)."""
        if self.source is Source.CONSOLE:
            return self.user or "nobody"
        if self.user:
            return f"{self.source.value}:{self.user}@{self.peer}" if self.peer else \
                f"{self.source.value}:{self.user}"
        return f"{self.source.value} {self.peer}".rstrip()


RoleOf = Callable[[str], str | None]  # a user's role now, None when there is no such user


class Commands:
    """The command layer of one running station."""

    def __init__(self, engine: Engine, sink: RecordSink, *, role_of: RoleOf,
                 tags: list[Tag] | tuple[Tag, ...] = (), alarms: StationAlarms | None = None,
                 source_roles: dict[Source, str] | None = None,
                 wallclock: Callable[[], float] = time.time,
                 monotonic: Callable[[], float] = time.monotonic,
                 standby: Callable[[], str | None] = lambda: None,
                 hand_over: Callable[[str], str | None] | None = None,
                 say: Words | None = None) -> None:
        self.engine = engine
        self.say = say or words()  # the station's language: its records and refusals
        self.standby = standby  # why this station of a pair takes no commands now (names the primary)
        self.hand_over = hand_over  # IntoStandBy by a user: None when done, else why not; None: no pair
        self.sink = sink
        self.role_of = role_of
        self.tags = {t.name: t for t in tags}
        self.alarms = alarms
        self.source_roles = {**ROLE_OF_SOURCE, **(source_roles or {})}
        self.wallclock = wallclock
        self.monotonic = monotonic
        self._lock = threading.Lock()
        self._refused: dict[tuple[str, str, str, str], list[float]] = {}  # key -> [since, count]
        self.refusals = 0  # every refusal, journaled or counted into one

    # --- the check -----------------------------------------------------------------------------

    def role(self, who: Who) -> str | None:
        """The role `who` acts with now: the user's (None when not a user), else the source's."""
        if who.user:
            return self.role_of(who.user)
        return self.source_roles.get(who.source)

    def denial(self, who: Who, action: Action, at_least: str | None = None,
               what: str | None = None) -> Refusal | None:
        """Why `who` may not do `action` (needing at least `at_least`), in parts; None when it may.
        Views ask this to disable a control and name the role in its tooltip."""
        role = needs(action, at_least)
        have = self.role(who)
        if have is not None and rank(have) >= rank(role):
            return None
        return Refusal(what or action.value, role, who.user, have or "")

    def may(self, who: Who, action: Action, at_least: str | None = None) -> bool:
        return self.denial(who, action, at_least) is None

    def grant(self, source: Source, role: str) -> None:
        """The role a user-less protocol acts with from now on: its station.toml section's `role`
        (a Modbus server read-only for everyone with "viewer"), set once its server is built."""
        if role not in ROLES:
            raise ValueError(f"role {role!r} is not one of {', '.join(ROLES)}")
        self.source_roles[source] = role

    # --- answers and refusals ------------------------------------------------------------------

    def refuse(self, who: Who, action: Action | str, target: str, reason: Reason, text: str,
               refusal: Refusal | None = None) -> Ticket:
        """A refused command: journaled (throttled), answered at once. `action` may be a word for
        what the policy has no entry for (a failed login, a refused channel)."""
        self._journal_refusal(who, action, target, reason, text)
        ticket: Ticket = Future()
        ticket.set_result(Answer(reason, text, refusal))
        return ticket

    def _journal_refusal(self, who: Who, action: Action | str, target: str, reason: Reason,
                         text: str) -> None:
        now = self.monotonic()
        principal = who.user or who.peer.rsplit(":", 1)[0]  # a client reconnecting keeps its host
        key = (who.source.value, principal, str(action), reason.value)
        with self._lock:
            self.refusals += 1
            entry = self._refused.get(key)
            if entry is not None and now - entry[0] < THROTTLE:
                entry[1] += 1
                return
            more = entry[1] if entry is not None else 0
            self._refused[key] = [now, 0]
            if len(self._refused) > 4096:  # bounded: forget the oldest causes
                for old in sorted(self._refused, key=lambda k: self._refused[k][0])[:1024]:
                    del self._refused[old]
        said = self.say(f"action {action}") if self.say.knows(f"action {action}") else action
        what = f"{said} {target}".strip()
        self.sink.put(Record(self.wallclock(), "operator", source=who.name,
                             text=self.say("refused more" if more else "refused", what=what, why=text,
                                           n=more)))

    def _check(self, who: Who, action: Action, target: str, at_least: str | None = None,
               what: str | None = None) -> Ticket | None:
        """A refusal ticket when the role does not allow it, else None."""
        why = self.denial(who, action, at_least, what)
        if why is None:
            return None
        # the journal names the action and target once: "refused write Пуск: needs the operator role"
        return self.refuse(who, action, target, Reason.DENIED, self.refusal_text(why), why)

    def refusal_text(self, why: Refusal) -> str:
        """The refusal for the role in the station's language, without its action (the record's)."""
        say = self.say

        def role(name: str) -> object:
            return phrase(f"role {name}") if name in ROLES else name

        if not why.user and why.user_role:
            return say("denied source", role=role(why.role), has=role(why.user_role))
        if not why.user:
            return say("denied nobody", role=role(why.role))
        if not why.user_role:
            return say("denied gone", user=why.user, role=role(why.role))
        return say("denied role", role=role(why.role), user=why.user, has=role(why.user_role))

    def _queue(self, who: Who, action: Action, target: str,
               apply: Callable[[Memory], None]) -> Ticket:
        """Queue `apply` (which journals) to the engine; the ticket is answered after the commit."""
        if (standby := self.standby()) is not None:
            return self.refuse(who, action, target, Reason.STANDBY, standby)
        ticket: Ticket = Future()

        def done(ok: bool) -> None:
            what = f"{self.say(f'action {action.value}')} {target}"
            ticket.set_result(APPLIED if ok else Answer(Reason.FAILED, self.say("not applied", what=what)))

        if not self.engine.command(apply, who.name, done):
            busy = self.engine.refusal() or BUSY
            reason = Reason.JOURNAL_FULL if busy == JOURNAL_FULL else Reason.BUSY
            text = self.say("journal full" if reason is Reason.JOURNAL_FULL else "busy")
            return self.refuse(who, action, target, reason, text)
        return ticket

    def _put(self, who: Who, text: str, **fields: object) -> None:
        self.sink.put(Record(self.wall(), "operator", source=who.name, text=text, **fields))  # type: ignore[arg-type]

    def wall(self) -> float:
        return self.engine.wall_time()

    # --- writes --------------------------------------------------------------------------------

    def write_tag(self, who: Who, name: str, value: object) -> Ticket:
        """Write a tag's physical value (OPC UA, MQTT, a faceplate): checked for its type and its
        physical range, journaled with the tag's name and unit."""
        tag = self.tags.get(name)
        if tag is None:
            return self.refuse(who, Action.WRITE, name, Reason.UNKNOWN, self.say("no tag", name=name))
        if (denied := self._check(who, Action.WRITE, name)) is not None:
            return denied
        if isinstance(value, str) or value is None or not isinstance(value, (bool, int, float)):
            return self.refuse(who, Action.WRITE, name, Reason.TYPE_MISMATCH,
                               self.say("no number", value=value))
        phy = float(value)
        if tag.type is TagType.BIT:
            if phy not in (0.0, 1.0):
                return self.refuse(who, Action.WRITE, name, Reason.OUT_OF_RANGE,
                                   self.say("not 0 or 1", value=value))
        else:
            lo, hi = write_range(tag)
            if not math.isfinite(phy) or not lo <= phy <= hi:
                return self.refuse(who, Action.WRITE, name, Reason.OUT_OF_RANGE,
                                   self.say("outside", value=value, lo=tag.format(lo), hi=tag.format(hi)))
        raw = tag.to_raw(phy)
        label = f"{tag.description} {name}".strip() if tag.description else name
        engine = self.engine
        if tag.type is TagType.BIT:
            return self._queue(who, Action.WRITE, name,
                               engine.bit_writer(tag.address, 1 if raw else 0, who.name, label))
        data = tag.encode(raw)
        if len(data) == 2:
            return self._queue(who, Action.WRITE, name, engine.word_writer(
                tag.address, int.from_bytes(data, "little"), who.name, label, tag.change))
        return self._queue(who, Action.WRITE, name, engine.bytes_writer(tag.address, data, who.name,
                                                                          f"{label}: {tag.format(phy)}"))

    def write_bit(self, who: Who, addr: int, value: int, *, label: str | None = None,
                  at_least: str | None = None) -> Ticket:
        """Write an HMI bit (a form's button, the Program view, a Modbus coil)."""
        target = label or fmt_octal(addr)
        at_least = _stopping(range(addr, addr + 1), value, at_least)
        if (denied := self._check(who, Action.WRITE, target, at_least)) is not None:
            return denied
        return self._queue(who, Action.WRITE, target, self.engine.bit_writer(addr, value, who.name, label))

    def write_word(self, who: Who, addr: int, value: int, *, label: str | None = None,
                   at_least: str | None = None,
                   describe: Callable[[int, int], str] | None = None) -> Ticket:
        target = label or fmt_octal(addr)
        if addr < IO_BITS:  # a word operand below 04000 is the 16 bits from that bit address
            at_least = _stopping(range(addr, addr + 16), (value >> (EMERGENCY_STOP - addr)) & 1
                                 if addr <= EMERGENCY_STOP < addr + 16 else 0, at_least)
        if (denied := self._check(who, Action.WRITE, target, at_least)) is not None:
            return denied
        return self._queue(who, Action.WRITE, target,
                           self.engine.word_writer(addr, value, who.name, label, describe))

    def write_bits(self, who: Who, addr: int, values: list[int]) -> Ticket:
        target = f"{fmt_octal(addr)}:{len(values)} bits"
        stop = values[EMERGENCY_STOP - addr] if addr <= EMERGENCY_STOP < addr + len(values) else 0
        at_least = _stopping(range(addr, addr + len(values)), stop, None)
        if (denied := self._check(who, Action.WRITE, target, at_least)) is not None:
            return denied
        return self._queue(who, Action.WRITE, target, self.engine.bits_writer(addr, values, who.name))

    def write_bytes(self, who: Who, addr: int, payload: bytes) -> Ticket:
        target = f"{fmt_octal(addr)}:{len(payload)}"
        if (denied := self._check(who, Action.WRITE, target)) is not None:
            return denied
        return self._queue(who, Action.WRITE, target, self.engine.bytes_writer(addr, payload, who.name))

    # --- alarms --------------------------------------------------------------------------------

    def _alarm(self, who: Who, action: Action, alarm_id: str,
               act: Callable[[StationAlarms], Callable[[], object]],
               check: Callable[[StationAlarms], object] | None = None) -> Ticket:
        """An alarm action: the alarm's transition record (naming the user) is its journal."""
        alarms = self.alarms
        if alarms is None:
            return self.refuse(who, action, alarm_id, Reason.NOT_RUNNING, self.say("no alarm system"))
        if (denied := self._check(who, action, alarm_id)) is not None:
            return denied
        try:
            if check is not None:
                check(alarms)
        except ValueError as e:  # AlarmError: unknown alarm, shelving without reason or duration
            reason = Reason.UNKNOWN if isinstance(e, UnknownAlarm) else Reason.INVALID
            return self.refuse(who, action, alarm_id, reason, str(e))
        run = act(alarms)
        return self._queue(who, action, alarm_id, lambda _mem: alarms.run_now(run))

    def acknowledge(self, who: Who, alarm_id: str, comment: str = "") -> Ticket:
        """`comment`: the operator's words, journaled with the acknowledgement."""
        return self._alarm(who, Action.ACKNOWLEDGE, alarm_id,
                           lambda a: lambda: a.system.acknowledge(alarm_id, who.name, comment=comment),
                           lambda a: a.system.get(alarm_id))

    def acknowledge_all(self, who: Who) -> Ticket:
        return self._alarm(who, Action.ACKNOWLEDGE, "all",
                           lambda a: lambda: a.system.acknowledge_all(who.name))

    def shelve(self, who: Who, alarm_id: str, reason: str, duration: float, once: bool = False) -> Ticket:
        """`once`: shelved until the condition next returns to normal, `duration` at most."""
        return self._alarm(who, Action.SHELVE, alarm_id,
                           lambda a: lambda: a.system.shelve(alarm_id, who.name, reason, duration, once=once),
                           lambda a: a.system.check_shelve(alarm_id, who.name, reason, duration))

    def unshelve(self, who: Who, alarm_id: str) -> Ticket:
        return self._alarm(who, Action.UNSHELVE, alarm_id,
                           lambda a: lambda: a.system.unshelve(alarm_id, who.name),
                           lambda a: a.system.get(alarm_id))

    def comment(self, who: Who, alarm_id: str, text: str) -> Ticket:
        """A comment on an alarm, journaled as a record of the alarm naming who."""
        return self._alarm(who, Action.COMMENT, alarm_id,
                           lambda a: lambda: a.system.comment(alarm_id, who.name, text),
                           lambda a: a.system.check_comment(alarm_id, who.name, text))

    def out_of_service(self, who: Who, alarm_id: str, out: bool = True) -> Ticket:
        return self._alarm(who, Action.OUT_OF_SERVICE, alarm_id,
                           lambda a: lambda: a.system.set_out_of_service(alarm_id, who.name, out),
                           lambda a: a.system.get(alarm_id))

    def silence(self, who: Who) -> Ticket:
        """Silence the horn: the alarms stay unacknowledged; journaled naming who."""
        if (denied := self._check(who, Action.SILENCE, "")) is not None:
            return denied
        alarms = self.alarms

        def apply(_mem: Memory) -> None:
            if alarms is not None:
                alarms.silence(self.wall())  # the consoles' sound and the horn bit
            self._put(who, self.say("silenced"))

        return self._queue(who, Action.SILENCE, "", apply)

    # --- forcing -------------------------------------------------------------------------------

    def _force(self, who: Who, action: Action, target: str,
               build: Callable[[], Callable[[Memory], None]]) -> Ticket:
        if (denied := self._check(who, action, target)) is not None:
            return denied
        try:
            apply = build()
        except ForceError as e:
            return self.refuse(who, action, target, Reason.INVALID, self.say(e.name, **e.values))
        return self._queue(who, action, target, apply)

    def force(self, who: Who, kind: Kind, addr: int, value: int | None = None) -> Ticket:
        forces = self.engine.forces
        return self._force(who, Action.FORCE, f"{kind} {given(addr)}",
                           lambda: forces.forcing(kind, addr, value, user=who.name))

    def force_tag(self, who: Who, name: str, phy: float | None = None) -> Ticket:
        tag = self.tags.get(name)
        if tag is None:
            return self.refuse(who, Action.FORCE, name, Reason.UNKNOWN, self.say("no tag", name=name))
        if phy is not None and tag.type is not TagType.BIT:
            lo, hi = write_range(tag)
            if not (math.isfinite(phy) and lo <= phy <= hi):
                return self.refuse(who, Action.FORCE, name, Reason.OUT_OF_RANGE,
                                   self.say("outside", value=phy, lo=tag.format(lo), hi=tag.format(hi)))
        forces = self.engine.forces
        return self._force(who, Action.FORCE, name, lambda: forcing_tag(forces, tag, phy, user=who.name))

    def unforce(self, who: Who, kind: Kind, addr: int) -> Ticket:
        forces = self.engine.forces
        return self._force(who, Action.UNFORCE, f"{kind} {given(addr)}",
                           lambda: forces.unforcing(kind, addr, user=who.name))

    def unforce_tag(self, who: Who, name: str) -> Ticket:
        tag = self.tags.get(name)
        if tag is None:
            return self.refuse(who, Action.UNFORCE, name, Reason.UNKNOWN, self.say("no tag", name=name))
        forces = self.engine.forces
        return self._force(who, Action.UNFORCE, name, lambda: unforcing_tag(forces, tag, user=who.name))

    def unforce_all(self, who: Who) -> Ticket:
        forces = self.engine.forces
        return self._force(who, Action.UNFORCE, "all", lambda: forces.unforcing_all(user=who.name))

    # --- run control ---------------------------------------------------------------------------

    def run(self, who: Who) -> Ticket:
        if (denied := self._check(who, Action.RUN, "NetPlc")) is not None:
            return denied
        engine = self.engine

        def apply(_mem: Memory) -> None:
            engine.start()
            self._put(who, self.say("NetPlc started"))

        return self._queue(who, Action.RUN, "NetPlc", apply)

    def stop(self, who: Who) -> Ticket:
        if (denied := self._check(who, Action.STOP, "NetPlc")) is not None:
            return denied
        engine = self.engine

        def apply(_mem: Memory) -> None:
            self._put(who, self.say(STOPPED_BY_COMMAND))  # first: NETPLC.STOPPED names who
            engine.stop()

        return self._queue(who, Action.STOP, "NetPlc", apply)

    def step(self, who: Who, lock: threading.Lock | None) -> Ticket:
        """One scan while NetPlc is stopped (Engine.step, between two scans of the scan thread:
        `lock` is the scan thread's); refused while it runs."""
        if (denied := self._check(who, Action.STEP, "NetPlc")) is not None:
            return denied
        engine = self.engine
        if lock is None:
            return self.refuse(who, Action.STEP, "NetPlc", Reason.NOT_RUNNING, self.say("not started"))
        if (standby := self.standby()) is not None:
            return self.refuse(who, Action.STEP, "NetPlc", Reason.STANDBY, standby)
        with lock:
            if engine.state is RunState.RUNNING:
                return self.refuse(who, Action.STEP, "NetPlc", Reason.INVALID, self.say("running"))
            engine.step()
            self._put(who, self.say("stepped", scan=engine.scan_counter), number=engine.scan_counter)
        ticket: Ticket = Future()
        ticket.set_result(APPLIED)
        return ticket

    # --- the hot-standby pair --------------------------------------------------------------------

    def into_standby(self, who: Who) -> Ticket:
        """IntoStandBy (seed 000): the primary hands its role to the standby at the end of its next
        scan, that scan's state the last it sends; answered once the record is committed."""
        if (denied := self._check(who, Action.INTO_STANDBY, "station")) is not None:
            return denied
        if (standby := self.standby()) is not None:
            return self.refuse(who, Action.INTO_STANDBY, "station", Reason.STANDBY, standby)
        if self.hand_over is None:
            return self.refuse(who, Action.INTO_STANDBY, "station", Reason.INVALID, self.say("not a pair"))
        if (why := self.hand_over(who.name)) is not None:
            return self.refuse(who, Action.INTO_STANDBY, "station", Reason.INVALID, why)
        self._put(who, self.say("handing over"))
        return self._answer_after_commit()

    # --- user administration ---------------------------------------------------------------------

    def manage_users(self, who: Who, target: str, change: Callable[[], str]) -> Ticket:
        """A change to the station's users (`target` the user it is about): `change()` makes it and
        says it for the journal. Users live in users.json, a file and not memory, so the change is
        made on the caller's thread (the scan never waits for a disk) once the role allows it, and
        answered once its record is committed; a change that cannot be made (a UserError: a name
        taken, an empty password) is refused INVALID with its words."""
        if (denied := self._check(who, Action.USERS, target)) is not None:
            return denied
        try:
            text = change()
        except UserError as e:
            return self.refuse(who, Action.USERS, target, Reason.INVALID,
                               self.say(e.name, **e.values) if e.name else str(e))
        self._put(who, text)
        return self._answer_after_commit()

    def _answer_after_commit(self) -> Ticket:
        """APPLIED once the records put so far are committed."""
        ticket: Ticket = Future()
        after_commit = getattr(self.sink, "after_commit", None)
        if after_commit is None:
            ticket.set_result(APPLIED)
        else:
            after_commit(lambda: ticket.set_result(APPLIED))
        return ticket

    def quit(self, who: Who) -> Ticket:
        """The right to stop the whole station; the caller stops it once this is answered. Not
        queued behind the outside writes and not refused for a full journal: an engineer must be
        able to stop a station whose disk is full (its last records are flushed at the stop)."""
        if (denied := self._check(who, Action.QUIT, "station")) is not None:
            return denied
        self._put(who, self.say("station quit"))
        ticket: Ticket = Future()
        ticket.set_result(APPLIED)
        return ticket


def _stopping(bits: range, value: int, at_least: str | None) -> str | None:
    """Setting the emergency-stop bit 03770 stops NetPlc: it needs the role Stop needs, whoever
    writes it and however (a button, a Modbus coil, a block of bits)."""
    if EMERGENCY_STOP in bits and value:
        role = POLICY[Action.STOP]
        if at_least is None or rank(role) > rank(at_least):
            return role
    return at_least


def write_range(tag: Tag) -> tuple[float, float]:
    """The physical values a client may write: PhyMin..PhyMax where the tag scales, else what its
    type holds."""
    s = tag.scaling
    if s is None:
        return tag.phy_limits
    return min(s.PhyMin, s.PhyMax), max(s.PhyMin, s.PhyMax)
