"""The ISA-18.2 alarm life cycle, evaluated once per scan on the engine thread.

Sources: analog limits HH/H/L/LL (deadband, on and off delay), a bit's value (`alarm_when`), the
program's NMSG messages of type 2 (alarm) and 3 (critical), a tag's bad quality, and NetPlc not
running (the station's one NETPLC.STOPPED alarm, with why in its text). Each alarm is one identity
(`LEVEL.HH`, `TRIG.ALARM`, `LEVEL.BAD`, `MSG3`) with a priority 1-4 and a text, and its state is
one of

    normal, active-unacknowledged, active-acknowledged, returned-unacknowledged,
    shelved (by a named operator, with a reason, until an end time; or once: until its condition
    next returns to normal, at most ONE_SHOT_LIMIT), suppressed (by design, while a condition bit
    is 1), out-of-service.

The last three lay over the first four: while one holds, the condition is still followed but
nothing is annunciated, and when it ends an alarm whose condition is active comes back
unacknowledged. A latching alarm stays active after its condition has gone until it is
acknowledged. While a tag's quality is bad its process alarms are frozen where they are (DIVAR:
"alarm only when not BAD"): a frozen value says nothing about the plant, neither that the alarm
has come nor that it has gone; the quality alarm says why. They also wait while the quality is
initial (no value from the plant yet, no quality alarm either: quality.py). While NetPlc is not
running every tag is frozen, its quality alarm too: a deliberate stop raises NETPLC.STOPPED only,
not one quality alarm per tag, and after the next start the values are initial until fresh data
lands, so nothing comes or goes before the plant has said so.

Every change of state is one `Transition`, journaled as one 'alarm' record (grp = priority,
type = new state, number = old state, source = the alarm's identity, value = the physical value,
text = what an operator reads, with the user where one acted). The state of every alarm is
handed to `on_change` whenever it changes and comes back as `saved`, so a restart changes
nothing an operator must act on (registrar/alarm_state.py keeps it on disk).

Thousands of limit alarms cost little per scan: the values are read and the conditions
(hysteresis included) computed by numpy for all alarms at once; Python only visits the alarms
whose condition differs from their state or that are waiting out a delay.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from enum import IntEnum, StrEnum
from typing import Any, Protocol

from app.scada.quality import code_flags
from app.scada.table import TagTable
from app.scada.tag import Tag, TagReader
from app.scada.words import Words, words
from netplc.lazy import lazy
from netplc.memory import MemoryView
from netplc.records import NullSink, Record, RecordSink

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it

PRIORITIES = {1: "critical", 2: "high", 3: "medium", 4: "low"}
MESSAGE_PRIORITY = {3: 1, 2: 2}  # NMSG type 3 critical -> priority 1, type 2 alarm -> priority 2
# NetPlc not running: the plant goes uncontrolled by the program and every value is frozen, so the
# operator must know at once (high: it sounds), deliberate stop or not.
STOPPED_ID, STOPPED_PRIORITY = "NETPLC.STOPPED", 2
# One of a hot-standby pair leading with no standby on its link: the plant has lost its redundancy
# (after a takeover, or with the partner down); the operator must know, and it sounds.
NO_STANDBY_ID, NO_STANDBY_PRIORITY = "PAIR.NO_STANDBY", 2
# A one-shot shelving ends when its alarm's condition returns to normal, and after this long at the
# latest: nothing stays shelved for good because its condition never came and went (ISA-18.2 wants
# shelving bounded; OPC UA Part 9 bounds a OneShotShelved alarm the same way).
ONE_SHOT_LIMIT = 24 * 3600.0


class State(IntEnum):
    NORMAL = 0
    UNACK = 1
    ACKED = 2
    RTNUN = 3
    SHELVED = 4
    SUPPRESSED = 5
    OUT_OF_SERVICE = 6

    @property
    def word(self) -> str:
        return _STATE_WORDS[self]


_STATE_WORDS = {State.NORMAL: "normal", State.UNACK: "active-unacknowledged",
                State.ACKED: "active-acknowledged", State.RTNUN: "returned-unacknowledged",
                State.SHELVED: "shelved", State.SUPPRESSED: "suppressed",
                State.OUT_OF_SERVICE: "out-of-service"}
IN_LIST = (State.UNACK, State.ACKED, State.RTNUN)  # what the alarm summary lists


class Source(StrEnum):
    LIMIT = "limit"
    DISCRETE = "discrete"
    MESSAGE = "message"
    QUALITY = "quality"
    STATION = "station"  # the station's own: NetPlc's run state (STOPPED_ID), its pair (NO_STANDBY_ID)


class AlarmError(ValueError):
    """An operator action that cannot be done (unknown alarm, shelving without a reason...), said
    in the alarm system's language."""


class UnknownAlarm(AlarmError):
    """No alarm by that identity."""


class CatalogMessage(Protocol):
    """A message of `messages.csv` (registrar.catalog.Message)."""

    number: int
    type: int
    text: str


@dataclass(frozen=True)
class AlarmDef:
    """What an alarm is; fixed while the station runs."""

    id: str
    source: Source
    text: str
    priority: int
    tag: str | None = None
    limit: float | None = None
    high: bool = True  # a limit alarm is active at or above its limit (HH, H), else at or below
    deadband: float = 0.0
    on_delay: float = 0.0
    off_delay: float = 0.0
    when: int = 1  # a discrete alarm is active while the bit has this value
    number: int | None = None  # NMSG message number
    latching: bool = False
    suppress_by: int | None = None  # HMI bit address


@dataclass
class Alarm:
    """One alarm's life-cycle state: what is persisted and what the summary shows."""

    defn: AlarmDef
    active: bool = False  # as annunciated: a latched alarm stays active after its condition has gone
    acked: bool = True
    acked_by: str = ""  # who acknowledged it, while it is acknowledged
    since: float = 0.0  # wall time of the last activation
    changed: float = 0.0  # wall time of the last transition
    value: float | None = None  # physical value at the last transition
    shelved_until: float | None = None
    shelved_by: str = ""
    reason: str = ""
    one_shot: bool = False  # shelved until the condition returns to normal (or shelved_until)
    out_of_service: bool = False
    oos_by: str = ""
    suppressed: bool = False
    detail: str = ""  # what the text alone cannot say: why NetPlc is not running
    comment: str = ""  # the last comment an operator gave it (acknowledging, or on its own)
    comment_by: str = ""

    @property
    def id(self) -> str:
        return self.defn.id

    @property
    def text(self) -> str:
        return f"{self.defn.text}: {self.detail}" if self.detail else self.defn.text

    @property
    def overlaid(self) -> bool:
        return self.out_of_service or self.shelved_until is not None or self.suppressed

    @property
    def state(self) -> State:
        if self.out_of_service:
            return State.OUT_OF_SERVICE
        if self.shelved_until is not None:
            return State.SHELVED
        if self.suppressed:
            return State.SUPPRESSED
        if self.active:
            return State.ACKED if self.acked else State.UNACK
        return State.NORMAL if self.acked else State.RTNUN


@dataclass(frozen=True, slots=True)
class AlarmRow:
    """One line of the alarm summary, frozen so another thread may show it while states change."""

    id: str
    priority: int
    state: State
    since: float  # wall time of the last activation
    changed: float  # wall time of the last transition
    value: float | None  # physical value at the last transition
    text: str
    tag: str | None = None
    shown: str = ""  # the value as an operator reads it: the tag's decimals and unit
    shelved_until: float | None = None
    shelved_by: str = ""
    reason: str = ""
    label: str = ""  # what the alarm is about, for a person: its tag's description, else its text

    @property
    def acked(self) -> bool:
        return self.state not in (State.UNACK, State.RTNUN)


def summary_order(row: AlarmRow) -> tuple[bool, int, float]:
    """Listed alarms by priority, then newest first; after them the shelved ones, likewise."""
    shelved = row.state is State.SHELVED
    return shelved, row.priority, -(row.changed if shelved else row.since)


PERSISTED = ("active", "acked", "acked_by", "since", "changed", "value", "shelved_until",
             "shelved_by", "reason", "one_shot", "out_of_service", "oos_by", "suppressed", "detail",
             "comment", "comment_by")
UNSHELVED = {"shelved_until": None, "shelved_by": "", "reason": "", "one_shot": False}


@dataclass(frozen=True)
class Transition:
    ts: float
    alarm: str
    old: State
    new: State
    priority: int
    value: float | None = None
    user: str | None = None
    text: str = ""

    def record(self) -> Record:
        return Record(self.ts, "alarm", grp=self.priority, type=int(self.new), source=self.alarm,
                      number=int(self.old), value=self.value, text=self.text)


def alarm_defs(table: TagTable, messages: Iterable[CatalogMessage] = (),
               station: bool = False, pair: bool = False, say: Words | None = None) -> list[AlarmDef]:
    """Every alarm of the tags and of the catalog's alarm and critical messages; with `station`,
    NetPlc's own NETPLC.STOPPED too, with `pair` PAIR.NO_STANDBY; texts in the language of `say`."""
    say = say or words()
    out: list[AlarmDef] = []
    for tag in table.tags:
        spec = table.alarms.get(tag.name)
        if spec is None:
            continue
        label = tag.description or tag.name
        common = {"priority": spec.priority, "tag": tag.name, "deadband": spec.deadband,
                  "on_delay": spec.on_delay, "off_delay": spec.off_delay, "latching": spec.latching,
                  "suppress_by": spec.suppress_by}
        for key, limit in spec.limits():
            text = say("limit", label=label, word=say(key), key=key, limit=tag.format(limit))
            out.append(AlarmDef(f"{tag.name}.{key}", Source.LIMIT, text, limit=limit,
                                high=key in ("HH", "H"), **common))
        if spec.alarm_when is not None:
            out.append(AlarmDef(f"{tag.name}.ALARM", Source.DISCRETE, f"{label} = {spec.alarm_when}",
                                when=spec.alarm_when, **common))
        if spec.quality_alarm:
            out.append(AlarmDef(f"{tag.name}.BAD", Source.QUALITY, say("bad quality", label=label),
                                spec.priority, tag=tag.name))
    for m in messages:
        if m.type in MESSAGE_PRIORITY:
            out.append(AlarmDef(f"MSG{m.number}", Source.MESSAGE, m.text, MESSAGE_PRIORITY[m.type],
                                number=m.number))
    if station:
        out.append(AlarmDef(STOPPED_ID, Source.STATION, say("not running"), STOPPED_PRIORITY))
    if pair:
        out.append(AlarmDef(NO_STANDBY_ID, Source.STATION, say("no standby"),
                            NO_STANDBY_PRIORITY))
    return out


@dataclass
class _Group:
    """The alarms of one source, as positions into the alarm arrays and the tags they read."""

    idx: list[int] = field(default_factory=list)
    tag: list[int] = field(default_factory=list)

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(self.idx, dtype=np.intp), np.array(self.tag, dtype=np.intp)


class AlarmSystem:
    """All alarms of a station: `evaluate` once per scan, operator actions from any caller on
    the engine thread (the runtime posts them there, as it does writes)."""

    def __init__(self, table: TagTable, messages: Iterable[CatalogMessage] = (), *,
                 sink: RecordSink | None = None, saved: Mapping[str, Mapping[str, Any]] | None = None,
                 on_change: Callable[[dict[str, dict[str, Any]]], None] | None = None,
                 clock: Callable[[], float] = time.time, station: bool = False, pair: bool = False,
                 language: str = "") -> None:
        """`station`: the alarm system of a running station, with NETPLC.STOPPED (`evaluate`'s
        `stopped` says why NetPlc is not running); `pair`: one of a hot-standby pair, with
        PAIR.NO_STANDBY (`evaluate`'s `no_standby` says why); `language`: the station's `Language`, in
        which every text and transition is built (app/scada/words.py)."""
        self.table = table
        self.sink: RecordSink = sink or NullSink()
        self.on_change = on_change
        self.clock = clock
        self.tags: list[Tag] = list(table.tags)
        self.reader = TagReader(self.tags)
        pos = {t.name: i for i, t in enumerate(self.tags)}
        self.say = words(language)
        self.defs = alarm_defs(table, messages, station, pair, self.say)
        self.alarms = [Alarm(d) for d in self.defs]
        self.by_id = {a.id: i for i, a in enumerate(self.alarms)}
        n = len(self.defs)
        groups = {s: _Group() for s in Source}
        self._msg: dict[int, int] = {}
        self._stopped: int | None = None  # NETPLC.STOPPED
        self._no_standby: int | None = None  # PAIR.NO_STANDBY
        for i, d in enumerate(self.defs):
            if d.tag is not None:
                groups[d.source].idx.append(i)
                groups[d.source].tag.append(pos[d.tag])
            elif d.id == NO_STANDBY_ID:
                self._no_standby = i
            elif d.source is Source.STATION:
                self._stopped = i
            else:
                self._msg[d.number or 0] = i
        self._lim_idx, self._lim_tag = groups[Source.LIMIT].arrays()
        lims = [self.defs[i] for i in groups[Source.LIMIT].idx]
        self._lim_sign = np.array([1.0 if d.high else -1.0 for d in lims])
        self._lim_limit = np.array([d.limit for d in lims], dtype=np.float64)
        self._lim_db = np.array([d.deadband for d in lims], dtype=np.float64)
        self._disc_idx, self._disc_tag = groups[Source.DISCRETE].arrays()
        self._disc_when = np.array([self.defs[i].when for i in groups[Source.DISCRETE].idx], dtype=np.float64)
        self._q_idx, self._q_tag = groups[Source.QUALITY].arrays()
        self._msg_idx = np.array(sorted(self._msg.values()), dtype=np.intp)
        self._proc_idx = np.concatenate((self._lim_idx, self._disc_idx))
        self._proc_tag = np.concatenate((self._lim_tag, self._disc_tag))
        self._tag_of = [pos[d.tag] if d.tag is not None else -1 for d in self.defs]
        self._on_delay = [d.on_delay for d in self.defs]
        self._off_delay = [d.off_delay for d in self.defs]
        self._suppressible = [i for i, d in enumerate(self.defs) if d.suppress_by is not None]
        self._hyst = np.zeros(n, dtype=bool)  # the condition, hysteresis applied
        self._cond = np.zeros(n, dtype=bool)  # the condition after its on/off delay
        self._pending = np.full(n, np.nan)  # since when the condition differs from _cond
        self._raw = np.zeros(len(self.tags))
        self._phy = np.zeros(len(self.tags))
        self._changed: set[int] = set()
        self._shelved: set[int] = set()  # the alarms whose shelving runs out by itself
        if saved:
            self.restore(saved)

    # --- persistence ---------------------------------------------------------------------------

    def restore(self, saved: Mapping[str, Mapping[str, Any]]) -> None:
        """Take back the states of a previous run (alarms no longer configured are left out).
        A condition that was active is taken as still active, so it raises nothing new; if it
        has gone, it returns through its off delay like any other."""
        for alarm_id, values in saved.items():
            i = self.by_id.get(alarm_id)
            if i is None:
                continue
            a = self.alarms[i]
            for key in PERSISTED:
                if key in values:
                    setattr(a, key, values[key])
            cond = bool(values.get("cond", a.active))
            self._cond[i] = self._hyst[i] = cond
            if a.shelved_until is not None:
                self._shelved.add(i)

    def adopt(self, states: Mapping[str, Mapping[str, Any]]) -> None:
        """The states of a hot-standby pair's primary (app/station/pair.py), taken as they are, so
        the standby's alarms are the primary's, acknowledgements, shelving and out-of-service
        included, and a takeover leaves nothing for an operator to do again. Kept and published as
        any change; journaled by the primary alone, which made them."""
        self.restore(states)
        self._changed.update(i for alarm_id in states if (i := self.by_id.get(alarm_id)) is not None)
        self._flush_changes()

    def states(self) -> dict[str, dict[str, Any]]:
        """Every alarm's state, as `on_change` hands each."""
        return {a.id: self.state_of(i) for i, a in enumerate(self.alarms)}

    def state_of(self, i: int) -> dict[str, Any]:
        a = self.alarms[i]
        out = {key: getattr(a, key) for key in PERSISTED}
        out["cond"] = bool(self._cond[i])
        out["state"] = a.state.word
        return out

    def _flush_changes(self) -> None:
        if self._changed and self.on_change is not None:
            changes = {self.alarms[i].id: self.state_of(i) for i in self._changed}
            self._changed.clear()
            self.on_change(changes)
        else:
            self._changed.clear()

    # --- per scan ------------------------------------------------------------------------------

    def evaluate(self, snapshot: MemoryView, now: float | None = None,
                 quality: np.ndarray | Sequence[int] | Mapping[str, int] | None = None,
                 messages: Iterable[int] = (), stopped: str = "", no_standby: str = "") -> list[Transition]:
        """One scan: `quality` holds each tag's quality code in table order (as
        `QualityMap.evaluate` gives it) or by tag name (None, or a tag not named: good),
        `messages` the NMSG numbers journaled in the scan, `stopped` why NetPlc is not running
        ("" while it runs), `no_standby` why a pair's primary has no standby ("" while it has).
        Returns the transitions, which are journaled as well."""
        if now is None:
            now = getattr(snapshot, "wall", 0.0) or self.clock()
        out: list[Transition] = []
        raw = self.reader.raw(snapshot)
        phy = self.reader.convert(raw)
        self._raw, self._phy = raw, phy
        hyst = self._hyst
        if isinstance(quality, Mapping):
            quality = [quality.get(t.name, 0) for t in self.tags]
        codes = np.asarray(quality, dtype=np.intp) if quality is not None else None
        alarmed_codes, held_codes = code_flags()
        alarmed = alarmed_codes[codes] if codes is not None else None
        held = held_codes[codes] if codes is not None else None
        frozen = None
        if held is not None and held.any():  # process alarms while held, quality ones unless alarmed
            frozen = np.concatenate((self._proc_idx[held[self._proc_tag]],
                                     self._q_idx[held[self._q_tag] & ~alarmed[self._q_tag]]))
        keep = hyst[frozen] if frozen is not None else None
        if len(self._lim_idx):
            x = self._lim_sign * (phy[self._lim_tag] - self._lim_limit)
            # the deadband keeps an alarm that is on (after its on delay) from returning; a condition
            # still waiting out its on delay ends below the limit itself (not raised at 89.9 % of 90)
            hyst[self._lim_idx] = (x >= 0) | (self._cond[self._lim_idx] & (x >= -self._lim_db))
        if len(self._disc_idx):
            hyst[self._disc_idx] = phy[self._disc_tag] == self._disc_when
        if len(self._q_idx):
            hyst[self._q_idx] = alarmed[self._q_tag] if alarmed is not None else False
        if len(self._msg_idx):
            hyst[self._msg_idx] = False
            for number in messages:
                i = self._msg.get(number)
                if i is not None:
                    hyst[i] = True
        for i, why in ((self._stopped, stopped), (self._no_standby, no_standby)):
            if i is not None:
                self._detail(i, why)
                hyst[i] = bool(why)
        differs = (hyst != self._cond) | ~np.isnan(self._pending)
        if frozen is not None:
            hyst[frozen] = keep
            self._pending[frozen] = np.nan
            differs[frozen] = False
        for i in np.flatnonzero(differs).tolist():
            self._debounce(i, bool(hyst[i]), now, out)
        for i in self._suppressible:
            on = bool(snapshot.get_hmi_bit(self.defs[i].suppress_by or 0))
            if on != self.alarms[i].suppressed:
                note = self.say("suppressed by design" if on else "suppression ended")
                self._overlay(i, now, out, None, note, suppressed=on)
        for i in sorted(self._shelved):
            a = self.alarms[i]
            if a.shelved_until is not None and now >= a.shelved_until:
                self._overlay(i, now, out, None, self.say("shelving ran out", user=a.shelved_by), **UNSHELVED)
        self._flush_changes()
        return out

    def _detail(self, i: int, why: str) -> None:
        """A station alarm (NETPLC.STOPPED, PAIR.NO_STANDBY) says why while it is active, and keeps
        it after it has gone."""
        a = self.alarms[i]
        if why and why != a.detail:
            a.detail = why
            self._changed.add(i)

    def _debounce(self, i: int, cond: bool, now: float, out: list[Transition]) -> None:
        if cond == self._cond[i]:
            self._pending[i] = np.nan
            return
        delay = self._on_delay[i] if cond else self._off_delay[i]
        if delay > 0:
            since = self._pending[i]
            if math.isnan(since):
                self._pending[i] = now
                return
            if now - since < delay:
                return
        self._pending[i] = np.nan
        self._cond[i] = cond
        a = self.alarms[i]
        old = a.state
        if cond and not a.active:
            a.active, a.acked, a.since = True, a.overlaid, now
        elif not cond and a.active and (a.overlaid or not a.defn.latching):
            a.active = False
        self._emit(i, old, now, out)
        if a.one_shot and not cond:
            self._overlay(i, now, out, None, self.say("one-shot ended", user=a.shelved_by),
                          **UNSHELVED)

    def _overlay(self, i: int, now: float, out: list[Transition], user: str | None, note: str,
                 **changes: Any) -> None:
        """Shelve, suppress, take out of service, or end one of them."""
        a = self.alarms[i]
        old, was = a.state, a.overlaid
        for key, value in changes.items():
            setattr(a, key, value)
        if a.shelved_until is None:
            self._shelved.discard(i)
        else:
            self._shelved.add(i)
        if a.overlaid and not was:
            a.acked = True  # out of the operator's list: nothing is left to acknowledge
        elif was and not a.overlaid:
            a.active = bool(self._cond[i])
            a.acked = not a.active  # an active condition comes back as a new alarm
            if a.active:
                a.since = now
        self._emit(i, old, now, out, user, note, always=user is not None)

    def _value(self, i: int) -> tuple[float | None, float | None]:
        """The physical and hardware value of the alarm's tag in the last evaluated scan."""
        t = self._tag_of[i]
        if t < 0:
            return None, None
        return float(self._phy[t]), float(self._raw[t])

    def _emit(self, i: int, old: State, now: float, out: list[Transition], user: str | None = None,
              note: str = "", always: bool = False) -> None:
        a = self.alarms[i]
        new = a.state
        if new == old and not always:
            return
        phy, raw = self._value(i)
        a.changed = now
        a.value = phy
        if not a.acked:
            a.acked_by = ""
        say = self.say
        text = f"{a.id} {say(old.word)} -> {say(new.word)}: {a.text}"
        t = self._tag_of[i]
        if phy is not None and raw is not None:
            tag = self.tags[t]
            shown = tag.format(phy) if not math.isnan(phy) else say("not a number")
            text += f"; {tag.name} = {shown}"
            if tag.scaling is not None:
                text += f" ({say('raw')} {raw:g})"
        if note:
            text += f"; {note}"
        if user:
            text += f"; {say('by', user=user)}"
        tr = Transition(now, a.id, old, new, a.defn.priority,
                        None if phy is None or math.isnan(phy) else phy, user, text)
        out.append(tr)
        self.sink.put(tr.record())
        self._changed.add(i)

    # --- operator actions ----------------------------------------------------------------------

    def _index(self, alarm_id: str) -> int:
        i = self.by_id.get(alarm_id)
        if i is None:
            raise UnknownAlarm(self.say("no alarm", alarm=alarm_id))
        return i

    def _act(self, action: Callable[[list[Transition]], None]) -> list[Transition]:
        out: list[Transition] = []
        action(out)
        self._flush_changes()
        return out

    def acknowledge(self, alarm_id: str, user: str, now: float | None = None,
                    comment: str = "") -> list[Transition]:
        """Acknowledge one alarm (a latched one whose condition has gone is reset by it), with the
        operator's `comment` if any (journaled with it, and kept as the alarm's last comment)."""
        i = self._index(alarm_id)
        return self._act(lambda out: self._ack(i, user, self.clock() if now is None else now, out, comment))

    def _ack(self, i: int, user: str, now: float, out: list[Transition], comment: str = "") -> None:
        a = self.alarms[i]
        old = a.state
        latched = a.defn.latching and a.active and not self._cond[i]
        if old is State.UNACK or old is State.RTNUN:
            a.acked, a.acked_by = True, user
        elif not (old is State.ACKED and latched):
            return
        if latched:
            a.active = False
        note = self.say("acknowledged" if old is not State.ACKED else "reset")
        if comment:
            a.comment, a.comment_by = comment, user
            note += f": {comment}"
        self._emit(i, old, now, out, user, note)

    def acknowledge_all(self, user: str, now: float | None = None) -> list[Transition]:
        """Acknowledge every unacknowledged alarm: one transition (and record) for each, naming it."""
        when = self.clock() if now is None else now
        todo = sorted((i for i, a in enumerate(self.alarms) if a.state in (State.UNACK, State.RTNUN)),
                      key=lambda i: (self.alarms[i].defn.priority, self.alarms[i].since))

        def run(out: list[Transition]) -> None:
            for i in todo:
                self._ack(i, user, when, out)

        return self._act(run)

    def shelve(self, alarm_id: str, user: str, reason: str, duration: float,
               now: float | None = None, once: bool = False) -> list[Transition]:
        """Shelve an alarm for `duration` seconds; it comes back by itself when they have run out.
        `once`: a one-shot shelving, which also ends when the condition next returns to normal."""
        i = self.check_shelve(alarm_id, user, reason, duration)
        when = self.clock() if now is None else now
        until = when + duration
        stamp = time.strftime(self.say.stamp, time.localtime(until))
        how = self.say("shelved once", stamp=stamp) if once else \
            self.say("shelved for", duration=duration, stamp=stamp)
        return self._act(lambda out: self._overlay(
            i, when, out, user, f"{how}: {reason}", shelved_until=until, shelved_by=user, reason=reason,
            one_shot=once))

    def check_shelve(self, alarm_id: str, user: str, reason: str, duration: float) -> int:
        """AlarmError unless the alarm exists and the shelving names its operator, a reason and a
        duration (what `shelve` checks, for callers that hand the shelving to another thread)."""
        i = self._index(alarm_id)
        if not user.strip():
            raise AlarmError(self.say("shelve nobody", alarm=alarm_id))
        if not reason.strip():
            raise AlarmError(self.say("shelve no reason", alarm=alarm_id))
        if not (math.isfinite(duration) and duration > 0):
            raise AlarmError(self.say("shelve no duration", alarm=alarm_id))
        return i

    def unshelve(self, alarm_id: str, user: str, now: float | None = None) -> list[Transition]:
        i = self._index(alarm_id)
        if self.alarms[i].shelved_until is None:
            return []
        when = self.clock() if now is None else now
        return self._act(lambda out: self._overlay(i, when, out, user, self.say("unshelved"), **UNSHELVED))

    def comment(self, alarm_id: str, user: str, text: str, now: float | None = None) -> list[Transition]:
        """An operator's comment on an alarm: journaled as a record of the alarm (its state stays),
        and kept as its last comment."""
        i = self.check_comment(alarm_id, user, text)
        a = self.alarms[i]
        when = self.clock() if now is None else now

        def run(out: list[Transition]) -> None:
            a.comment, a.comment_by = text, user
            self._emit(i, a.state, when, out, user, self.say("comment", text=text), always=True)

        return self._act(run)

    def check_comment(self, alarm_id: str, user: str, text: str) -> int:
        """AlarmError unless the alarm exists and the comment names its operator and says something."""
        i = self._index(alarm_id)
        if not user.strip():
            raise AlarmError(self.say("comment nobody", alarm=alarm_id))
        if not text.strip():
            raise AlarmError(self.say("comment empty", alarm=alarm_id))
        return i

    def set_out_of_service(self, alarm_id: str, user: str, out_of_service: bool = True,
                           now: float | None = None) -> list[Transition]:
        i = self._index(alarm_id)
        if self.alarms[i].out_of_service == out_of_service:
            return []
        when = self.clock() if now is None else now
        note = self.say("taken out of service" if out_of_service else "returned to service")
        return self._act(lambda out: self._overlay(i, when, out, user, note, out_of_service=out_of_service,
                                                   oos_by=user if out_of_service else ""))

    # --- for the summary and the banner ----------------------------------------------------------

    def get(self, alarm_id: str) -> Alarm:
        return self.alarms[self._index(alarm_id)]

    def listed(self) -> list[Alarm]:
        """Active and unacknowledged alarms, by priority, then newest first."""
        return sorted((a for a in self.alarms if a.state in IN_LIST),
                      key=lambda a: (a.defn.priority, -a.since))

    def row(self, alarm_id: str) -> AlarmRow | None:
        """The alarm's line of the summary; None if it is not on it (normal, suppressed, out of
        service)."""
        i = self._index(alarm_id)
        a = self.alarms[i]
        state = a.state
        if state not in IN_LIST and state is not State.SHELVED:
            return None
        t = self._tag_of[i]
        tag = self.tags[t] if t >= 0 else None
        shown = "" if a.value is None else tag.format(a.value) if tag is not None else f"{a.value:g}"
        label = (tag.description or tag.name) if tag is not None else a.defn.text
        return AlarmRow(a.id, a.defn.priority, state, a.since, a.changed, a.value, a.text,
                        a.defn.tag, shown, a.shelved_until, a.shelved_by, a.reason, label)

    def rows(self) -> tuple[AlarmRow, ...]:
        """The summary: listed alarms (by priority, newest first), then the shelved ones."""
        rows = (self.row(a.id) for a in self.alarms)
        return tuple(sorted((r for r in rows if r is not None), key=summary_order))

    def counts(self) -> dict[int, int]:
        """How many alarms of each priority are listed."""
        out = dict.fromkeys(PRIORITIES, 0)
        for a in self.alarms:
            if a.state in IN_LIST:
                out[a.defn.priority] += 1
        return out

    def first_unacknowledged(self) -> Alarm | None:
        """The highest-priority unacknowledged alarm, newest first: what the banner shows."""
        return next((a for a in self.listed() if not a.acked), None)
