"""A remote station as the data source of the console's views: the same `readings` signal the local
workstation's `RuntimeBridge` gives (one scan's memory with the quality of everything in it), so
a form view refreshes from either without knowing which one it has; besides it the station's
files (its forms to show), its alarms and the link's state.

The session runs on its own thread (`ConsoleClient`, asyncua); each change there pokes this
object, which takes the newest state on the GUI thread (coalesced: a GUI that lags skips to the
newest, as the bridge does). Quality is judged here as the station judges it, from the station's
program and tags (its files), NetPlc's run state and the nodes' links as the station reads them;
while the link to the station is down every operand is "station unreachable", its own quality,
so nothing looks live that is not.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import logging
import threading
from dataclasses import dataclass

import numpy as np
from PySide6.QtCore import QObject, Signal

from app.publish.console import ConsoleClient, Files
from app.publish.memory_items import NOTHING, Ranges
from app.scada.alarms import AlarmRow, summary_order
from app.scada.horn import Horn
from app.scada.quality import LinkView, Operands, Quality, QualityMap
from app.scada.readings import Reading, Readings
from app.scada.table import TagTable, read_tags
from hmi_forms.form import Form, load_forms
from hmi_forms.widgets.journal import Page
from netplc.memory import Snapshot
from netplc.program import Program, ProgramError, parse, parse_file, read_symbols
from registrar.query import Filter
from registrar.reading import Row

logger = logging.getLogger(__name__)

JOURNAL_WAIT_S = 10.0  # a page of the journal the station does not give within this is "unreadable"


@dataclass(frozen=True)
class Unreachable(Readings):
    """The last scan the console had, every operand of it "station unreachable"."""

    def address(self, address: int, nbytes: int = 2) -> Quality:
        return Quality.UNREACHABLE

    def quality(self, name: str) -> Quality:
        return Quality.UNREACHABLE

    def judge(self, operands: Operands) -> np.ndarray:
        return np.full(len(operands.member), Quality.UNREACHABLE, dtype=np.int8)

    def tag(self, name: str) -> Reading:
        return dataclasses.replace(super().tag(name), quality=Quality.UNREACHABLE)

    def live(self, snapshot: Snapshot) -> Snapshot:
        return snapshot


@dataclass
class Loaded:
    """The station's parts as the console loads them from its files."""

    files: Files
    symbols: dict[str, int]
    tags: TagTable
    program: Program
    forms: list[Form]
    problems: list[str]


def load_files(files: Files) -> Loaded:
    """The forms, tags, symbols and program of the station's files, and what did not load."""
    problems: list[str] = []
    symbols: dict[str, int] = {}
    if (path := files.part("symbols")) is not None:
        symbols, errors = read_symbols(path)
        problems += [str(e) for e in errors]
    tags = TagTable()
    if (path := files.part("tags")) is not None:
        tags, errors_ = read_tags(path, symbols)
        problems += errors_
    program = parse("", source="<no program>")
    if (path := files.part("program")) is not None:
        try:
            program = parse_file(path, symbols)
        except ProgramError as e:
            problems += e.problems
    forms: list[Form] = []
    if (path := files.part("forms")) is not None:
        forms, form_problems = load_forms(path, symbols, station=files.folder, tags=tags)
        problems += form_problems
    else:
        problems.append("the station serves no forms (no HMIload, or it lies outside the station folder)")
    return Loaded(files, symbols, tags, program, forms, problems)


class RemoteJournal:
    """The station's journal as the journal dock reads it (app/gui/journal.py), on the dock's worker
    thread: the station object's event history of the day, newest first. A station that does not
    answer is the dock's "archive unreadable" with the reason (an OSError, as a local file's)."""

    def __init__(self, client: ConsoleClient) -> None:
        self.client = client
        self._day: dt.date | None = None
        self._rows: list[Row] = []  # the day's newest records as last read, newest first
        self._seen: object = None  # the station's count of journal events the rows hold
        self._misses = 0
        self._switches = client.switches  # the pair's other station keeps a journal of its own

    def page(self, day: dt.date, flt: Filter, limit: int, count: bool) -> Page | None:
        """The day's newest page: read whole once, then only what came since its newest record,
        and only when the station's count of journal events changed (an event counts before its
        record is committed: it is looked for again at the next pages, three times at most)."""
        head = self.client.journal_events
        try:
            if day != self._day or not self._rows or self.client.switches != self._switches:
                switches = self.client.switches
                self._rows = self.client.journal(day, limit).result(JOURNAL_WAIT_S)
                self._day, self._seen, self._misses, self._switches = day, head, 0, switches
            elif head != self._seen:
                newest = self._rows[0]
                new = [r for r in self.client.journal(day, limit, newest.ts).result(JOURNAL_WAIT_S)
                       if r.id > newest.id]
                self._rows = (new[::-1] + self._rows)[:limit]
                self._misses = 0 if new else self._misses + 1
                if isinstance(head, int) and isinstance(self._seen, int) and new:
                    self._seen = min(head, self._seen + len(new))
                if self._misses >= 3 or not isinstance(head, int) or not isinstance(self._seen, int):
                    self._seen, self._misses = head, 0
        except (ConnectionError, TimeoutError) as e:
            self._rows = []  # read whole again once the station answers: it may have restarted
            raise OSError(f"the station's journal: {e or type(e).__name__}") from None
        kinds = flt.kinds
        shown = [r for r in self._rows if kinds is None or r.kind in kinds]
        return Page(day, shown, len(shown) if len(self._rows) < limit else None)

    def close(self) -> None:
        pass  # the session is the console's: closed with it


class RemoteAlarms:
    """The station's alarms as the alarm views read the local alarm system's (an `AlarmSource`:
    `version`, `summary` in the summary's order, the horn)."""

    def __init__(self) -> None:
        self.version = 0
        self.summary: list[AlarmRow] = []
        self.horn = Horn()  # what sounds, worked out from the station's rows as the station does
        self._horn = threading.Lock()  # a Silence lands on the client's thread, the rows on the GUI's

    def show(self, rows: tuple[AlarmRow, ...]) -> None:
        self.summary = sorted(rows, key=summary_order)
        with self._horn:
            self.horn.update(self.summary)
        self.version += 1

    def silence(self, now: float) -> None:
        """The station took this console's Silence (StationCommands): what sounds now stops here
        too, as it did at the station."""
        with self._horn:
            self.horn.silence(now)


class StationSource(QObject):
    """`readings` as the bridge gives them; `loaded` when the station's files changed; `alarms`
    the station's alarm rows; `link` "" while the station answers, else why not. `covered`: the
    parts of the memory that hold the station's values in the readings last given (the console
    watches only what its views want: a view is shown readings that cover what it reads)."""

    readings = Signal(object)  # Readings (Unreachable while the link is down)
    loaded = Signal(object)  # Loaded
    alarms = Signal(object)  # tuple[AlarmRow, ...]
    link = Signal(str)
    _poke = Signal()  # from the client's thread

    def __init__(self, client: ConsoleClient, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.client = client
        self.current: Loaded | None = None
        self.station_alarms = RemoteAlarms()
        self.quality_map: QualityMap | None = None
        self._snapshot: Snapshot | None = None
        self.covered: Ranges = NOTHING
        self._files: Files | None = None
        self._alarms: tuple[AlarmRow, ...] | None = None
        self._error: str | None = None
        self._waiting = False
        self._lock = threading.Lock()
        self._poke.connect(self._deliver)
        client.changed = self._changed
        self._changed()  # what the client has already (it logged in before this was made)

    def _changed(self) -> None:
        with self._lock:
            if self._waiting:
                return
            self._waiting = True
        self._poke.emit()

    def _deliver(self) -> None:
        with self._lock:
            self._waiting = False
        client = self.client
        files, error, shown, alarms = client.files, client.error, client.shown, client.alarms
        snapshot, covered = shown if shown is not None else (None, NOTHING)
        if files is not None and files is not self._files:
            self._files = files
            self.current = load_files(files)
            self.quality_map = QualityMap(self.current.program, self.current.tags.tags)
            self.loaded.emit(self.current)
            self._snapshot = None  # the new views are shown the scan they have not seen
        if error != self._error:
            self._error = error
            self.link.emit(error)
            if error and self._snapshot is not None and self.quality_map is not None:
                last = dataclasses.replace(self._snapshot)  # a new scan to the views: judged again
                self.readings.emit(Unreachable(last, self.quality_map, LinkView(), np.zeros(0, np.int8)))
        if not error and snapshot is not None and snapshot is not self._snapshot and \
                self.quality_map is not None:
            self._snapshot, self.covered = snapshot, covered
            links = LinkView(running=snapshot.state == "running", links=dict(client.links),
                             forced=[a for f in snapshot.forces for a in f.operands])
            self.readings.emit(Readings(snapshot, self.quality_map, links,
                                        self.quality_map.evaluate(snapshot, links)))
        if alarms != self._alarms:
            self._alarms = alarms
            self.station_alarms.show(alarms)
            self.alarms.emit(alarms)

    def stop(self) -> None:
        self.client.changed = lambda: None
        self.client.close()
