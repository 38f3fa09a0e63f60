"""Tags, quality and alarms of a running station, wired the way the runtime needs them.

`StationAlarms` loads `tags.csv`, works out from the program which node fills which tag, takes
back the alarm states of the last run, and then, attached to the engine, runs once per scan on
the engine thread: each tag's quality from the exchange's links and data ages and NetPlc's run
state, then the alarms over that scan's snapshot and the NMSG numbers journaled in it. Each scan
ends by publishing `readings` (app/scada/readings.py): the one place the HMI, the journal and
the publishers read a value's quality. Operator actions are posted to the engine thread, as
writes are, so the alarm states have one writer. No Qt: the workstation and `--no-gui` share it.

Start-up truth: a node's data is expected only from the first scan of this run of NetPlc in which
its first exchange attempt is done (`LinkView.since`); before that its tags are "initial", not
comm-fail, so a start raises no quality alarm for a node that simply has not answered yet.

NetPlc not running (the operator's Stop, an emergency stop by bit 03770, HLT, the watchdog): every
tag is "not running" and its alarms, quality alarms included, stay as they were; one station alarm,
NETPLC.STOPPED, says that NetPlc is not running and why (`stop_reason`). When it runs again the
alarm returns, and the tags are initial until fresh data lands, as at start.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from app.scada.alarms import AlarmRow, AlarmSystem, CatalogMessage, summary_order
from app.scada.horn import Horn
from app.scada.quality import LinkView, QualityMap
from app.scada.readings import Readings
from app.scada.series import SeriesQuality
from app.scada.table import TagTable, load_tags
from app.scada.words import Words, words
from netplc.address import EMERGENCY_STOP, fmt_octal
from netplc.engine import Engine, RunState
from netplc.exchange import Exchange
from netplc.lazy import lazy
from netplc.memory import Memory, Snapshot
from netplc.program import Program
from netplc.records import Record, RecordSink
from registrar.alarm_state import AlarmStateFile

np = lazy("numpy")  # loaded at first use: only a station with tags or forms needs it

STATE_FILE = "alarms.sqlite"  # next to the archive
EMERGENCY_STOP_CODE = 11  # the engine's stop code for the emergency-stop bit
PUBLISH_EVERY = 0.25  # s of engine time between two rebuilds of the summary during a flood


class StationAlarms:
    def __init__(self, tags: Path | None, program: Program, messages: list[CatalogMessage], sink: RecordSink,
                 state_file: Path, symbols: dict[str, int] | None = None,
                 regdata: Mapping[str, Sequence[tuple[int, int]]] | None = None,
                 no_standby: Callable[[], str] | None = None, horn: int | None = None,
                 language: str = "") -> None:
        """TagError (every problem of tags.csv) if the tags cannot be used. `regdata`: the forms'
        RegData elements by name, with their operands (app/scada/series.py); `no_standby`: one of a
        hot-standby pair, why it has no standby now ("" while it has), for PAIR.NO_STANDBY; `horn`:
        the HMI bit set while an alarm sounds (station.toml `alarm_horn`); `language`: the station's
        `Language`, of every alarm text."""
        self.table = load_tags(tags, symbols, words(language)) if tags is not None else TagTable()
        self.quality_map = QualityMap(program, self.table.tags)
        self.sink = sink
        self.series = SeriesQuality(program, regdata or {})
        self.state = AlarmStateFile(state_file, sink, say=words(language))
        self.system = AlarmSystem(self.table, messages, sink=sink, saved=self.state.load(),
                                  on_change=self._changed, station=True, pair=no_standby is not None,
                                  language=language)
        self.no_standby = no_standby or (lambda: "")
        self.quality = np.zeros(len(self.table.tags), dtype=np.int8)  # of the last scan, by tag
        self.readings: Readings | None = None  # of the last scan; None before the first
        # The alarm summary, rebuilt on the engine thread after states changed, from the rows of
        # the alarms that changed (a flood costs one row per transition and one sort per rebuild,
        # at most every PUBLISH_EVERY); `version` counts the rebuilds, so a view redraws only when
        # something changed. Operator actions are published at once.
        self.summary: tuple[AlarmRow, ...] = self.system.rows()
        self.version = 0
        self._rows = {r.id: r for r in self.summary}
        self._dirty: set[str] = set()
        self._published = float("-inf")  # engine time of the last rebuild
        self.engine: Engine | None = None
        self.horn = Horn(horn)  # what is to be heard, and the horn bit (app/scada/horn.py)
        self.exchange: Exchange | None = None
        self._messages: list[int] = []
        self._since: dict[int, int] = {}  # node -> first scan of this run with its link known
        self._stopped_by = ""  # who stopped NetPlc through the command layer (its record), while stopped
        self._unsent: dict[str, dict[str, Any]] | None = None  # changed states for a pair's standby
        # told the ids of the alarms whose states a pair's standby adopted (on the engine thread):
        # those changes are journaled by the primary alone, so a record observer never sees them
        self.adopted: list[Callable[[list[str]], None]] = []

    def attach(self, engine: Engine, exchange: Exchange | None) -> None:
        """Evaluate after every scan of `engine`; start saving states."""
        self.engine, self.exchange = engine, exchange
        engine.subscribe(self.on_scan)
        self.horn.update(self.summary)  # alarms restored unacknowledged sound again
        self._sound()
        self.state.start()

    def observe(self, record: Record) -> None:
        """The runtime's record observer: collects the NMSG numbers of the scan being run."""
        if record.kind == "message" and record.number is not None:
            self._messages.append(record.number)
        elif record.kind == "operator" and record.text == self.system.say(STOPPED_BY_COMMAND):
            self._stopped_by = record.source or ""

    def on_scan(self, snapshot: Snapshot) -> None:
        ex = self.exchange
        running = snapshot.state == RunState.RUNNING
        if not running:
            self._since.clear()  # after a stop, data is expected afresh from the next start
        else:
            self._stopped_by = ""
            for n in ex.configs if ex is not None else ():
                if n not in self._since and ex.link_known(n):  # type: ignore[union-attr]
                    self._since[n] = snapshot.scan
        links = LinkView(running=running,
                         links={n: ex.link_up(n) for n in ex.configs} if ex is not None else {},
                         refreshed=dict(ex.refreshed) if ex is not None else {},
                         since=dict(self._since) if ex is not None else None,
                         forced=[a for f in snapshot.forces for a in f.operands])
        self.quality = self.quality_map.evaluate(snapshot, links)
        self.readings = Readings(snapshot, self.quality_map, links, self.quality)
        if self.engine is not None and self.engine.follower:
            self._messages.clear()  # a pair's standby: the primary's alarm states are adopted, and
            return  # the primary journals the transitions and the series, which it forwards
        for record in self.series.evaluate(snapshot, links, snapshot.wall):
            self.sink.put(record)
        messages, self._messages = self._messages, []
        self.system.evaluate(snapshot, snapshot.wall, self.quality, messages,
                             "" if running else stop_reason(snapshot.state, self._stopped_by,
                                                                   self.system.say),
                             self.no_standby())
        if self._dirty and snapshot.time - self._published >= PUBLISH_EVERY:
            self._publish(snapshot.time)

    def stamp(self, record: Record) -> Record:
        """A data record (NSTORE, RegData) with its value's quality as its text when not good,
        as of the last scan; the runtime's sink calls it on the engine thread."""
        return self.series.stamp(record)

    def _changed(self, changes: dict[str, dict[str, Any]]) -> None:
        self.state.update(changes)
        self._dirty.update(changes)
        if self._unsent is not None:
            self._unsent.update(changes)

    def changes_for_standby(self, whole: bool = False) -> dict[str, dict[str, Any]]:
        """On the engine thread: the states changed since the last call (the first call starts
        keeping them), or with `whole` every alarm's; what a pair's primary sends its standby."""
        unsent, self._unsent = self._unsent or {}, {}
        return self.system.states() if whole else unsent

    def adopt(self, states: dict[str, dict[str, Any]]) -> None:
        """On the engine thread: the primary's states, on its standby (AlarmSystem.adopt)."""
        if states:
            self.run_now(lambda: self.system.adopt(states))
            ids = [alarm_id for alarm_id in states if alarm_id in self.system.by_id]
            for observer in list(self.adopted):
                observer(ids)

    def _publish(self, now: float | None = None) -> None:
        for alarm_id in self._dirty:
            row = self.system.row(alarm_id)
            if row is None:
                self._rows.pop(alarm_id, None)
            else:
                self._rows[alarm_id] = row
        self._dirty.clear()
        self.summary = tuple(sorted(self._rows.values(), key=summary_order))
        self.version += 1
        if self.horn.update(self.summary):
            self._sound()
        if now is not None:
            self._published = now

    def run_now(self, action: Callable[[], object]) -> None:
        """On the engine thread: an operator action on the alarms (the command layer's), then the
        summary published at once."""
        action()
        if self._dirty:
            self._publish()

    def _post(self, action: Callable[[], object]) -> None:
        def run() -> None:
            self.run_now(action)

        if self.engine is None:
            run()
        else:
            self.engine.post(lambda _mem: run())

    # Operator actions: refused at once (AlarmError) for an unknown alarm or a shelving without
    # its operator, reason or duration; done at the start of the next scan.

    def acknowledge(self, alarm_id: str, user: str) -> None:
        self.system.get(alarm_id)
        self._post(lambda: self.system.acknowledge(alarm_id, user))

    def acknowledge_all(self, user: str) -> None:
        self._post(lambda: self.system.acknowledge_all(user))

    def shelve(self, alarm_id: str, user: str, reason: str, duration: float) -> None:
        self.system.check_shelve(alarm_id, user, reason, duration)
        self._post(lambda: self.system.shelve(alarm_id, user, reason, duration))

    def unshelve(self, alarm_id: str, user: str) -> None:
        self.system.get(alarm_id)
        self._post(lambda: self.system.unshelve(alarm_id, user))

    def set_out_of_service(self, alarm_id: str, user: str, out_of_service: bool = True) -> None:
        self.system.get(alarm_id)
        self._post(lambda: self.system.set_out_of_service(alarm_id, user, out_of_service))

    def silence(self, now: float) -> None:
        """On the engine thread (the command layer's Silence): what sounds now stops."""
        self.horn.silence(now)
        self._sound()

    def follow_horn(self, silenced_at: float) -> None:
        """On the engine thread of a pair's standby: the primary's last silence, so its horn
        sounds for what the primary's does, and goes on so after a takeover (nothing to silence
        again)."""
        if silenced_at != self.horn.silenced_at:
            self.horn.silenced_at = silenced_at
            self.horn.update(self.summary)

    def _sound(self) -> None:
        engine = self.engine
        if engine is not None and self.horn.bit is not None:
            engine.post(self._write_horn)

    def _write_horn(self, mem: Memory) -> None:
        """The horn bit, on a station that leads: a pair's standby holds the primary's memory, its
        horn bit included, which its own adopted states must not overwrite."""
        if self.engine is None or not self.engine.follower:
            self.horn.write(mem)

    def close(self) -> None:
        """After the scan thread has stopped: write the last states."""
        self.state.close()



STOPPED_BY_COMMAND = "NetPlc stopped"  # the catalogue's name of the command layer's Stop record, naming who


def stop_reason(state: str, by: str = "", say: Words | None = None) -> str:
    """Why NetPlc is not running, from the snapshot's run state (Engine.state_text), with its
    stop code; `by`: who stopped it through the command layer (the journal's name of them);
    in the language of `say`."""
    say = say or words()
    if state == RunState.HALTED:
        return say("halted")
    if state == f"{RunState.STOPPED}, code {EMERGENCY_STOP_CODE}":
        return say("emergency stop", bit=fmt_octal(EMERGENCY_STOP), code=EMERGENCY_STOP_CODE)
    if state == RunState.STOPPED:
        return say("stopped by", user=by) if by else say("stopped")
    return state
