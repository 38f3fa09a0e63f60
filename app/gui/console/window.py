"""The remote console (`main.py console opc.tcp://HOST:PORT/PATH`): the operator's forms and alarm
banner of a station running elsewhere, with no NetPlc, exchange or archive of its own.

Its views are the workstation's own (the form view in its zoom area, a tag's faceplate from its
elements, the alarm banner, the health strip, the journal dock, the header); what differs is
where their data comes from: a `StationSource` and a `RemoteJournal` (source.py) instead of the
in-process runtime's bridge and the archive's file, and a `StationArchiveSource` (archive.py) as
the archive that the trends' history, the faceplates' hour, the run-time trend window and the
journal viewer read. Everything it does is done by the user logged in at the station, through the
station's command layer: a form's write is the station's WriteBit or WriteWord method, a
faceplate's its WriteTag, ForceTag or UnforceTag, an acknowledgement its Acknowledge; the
station checks the role, journals with the user's name and answers, and a refusal is said in the
status bar naming the role it needs.
Forms come from the station (its Files): a form saved there is shown here at the next poll.
Of NetPlc's memory the console watches what the form shown reads (its elements' operands), and the
whole of it while a Program view is open; the form shown is refreshed from readings that cover it,
a form not shown is not refreshed (it is, from the first readings that cover it, once shown), but
for "station unreachable", which every form shows at once.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QTimer
from PySide6.QtGui import QAction, QCloseEvent, QKeySequence
from PySide6.QtWidgets import (
    QMainWindow,
    QMessageBox,
    QStatusBar,
    QWidget,
)

from app.authority import Action, Answer, Refusal, Source, Ticket, Who, write_range
from app.gui import i18n, words
from app.gui.alarm_summary import AlarmSummary
from app.gui.application import application
from app.gui.bridge import Answers
from app.gui.console.archive import StationArchiveSource
from app.gui.console.source import Loaded, RemoteJournal, StationSource, Unreachable
from app.gui.faceplate import Console, Faceplates
from app.gui.journal import JournalDock
from app.gui.main_window import (
    REFUSAL_MS,
    _placeholder,
    _problems_page,
    _quit_on_signals,
    bottom_docks,
    station_frame,
)
from app.gui.monitor.login import logged_in
from app.gui.monitor.source import OpcUaSource
from app.gui.monitor.window import ProgramWindow
from app.gui.rights import Rights
from app.gui.trend_history import ArchiveSeries, TrendHistory
from app.gui.trend_window import TrendWindow
from app.gui.viewer import ViewerWindow
from app.gui.zoom import ZoomArea
from app.publish.console import ConsoleClient, StationCommands
from app.publish.memory_items import NOTHING, WHOLE, Ranges, ranges_of
from app.scada.alarms import AlarmRow, alarm_defs
from app.scada.readings import Readings
from app.scada.tag import Tag, TagType
from app.scada.trends import TrendBook
from app.scada.words import words as words_of
from app.station import heap
from hmi_forms.elements.base import Writer
from hmi_forms.elements.reads import operands
from hmi_forms.elements.target import CommandTarget
from hmi_forms.widgets.form_view import FormView
from netplc.problems import Problems

logger = logging.getLogger(__name__)

STATUS_MS = 1000


class RemoteTarget(CommandTarget):
    """The station's command layer, reached over its endpoint, as the form elements' Target and
    the faceplates': the station names a tag's write with the tag and journals it with the
    console's user (so no tags here: the view says the element's label); a faceplate's commands
    are the station's WriteTag, ForceTag and UnforceTag."""

    def __init__(self, client: ConsoleClient, answers: Answers) -> None:
        super().__init__(lambda user: Who(user, Source.OPCUA), (), answers.follow, words.answer)
        self.client = client

    def bit(self, who: Who, addr: int, value: int, label: str | None, at_least: str | None) -> Ticket:
        return self.client.write_bit(addr, value, label, at_least)

    def word(self, who: Who, addr: int, value: int, label: str | None, at_least: str | None,
             describe: Callable[[int, int], str] | None = None) -> Ticket:
        return self.client.write_word(addr, value, label, at_least)

    def denial(self, who: Who, action: Action, what: str | None = None) -> Refusal | None:
        return self.client.denial(action, None, what)

    def write_tag(self, who: Who, tag: Tag, value: float) -> Ticket:
        return self._tag(Action.WRITE, tag, "WriteTag", float(value))

    def force_tag(self, who: Who, tag: Tag, phy: float | None) -> Ticket:
        return self._tag(Action.FORCE, tag, "ForceTag", phy)

    def unforce_tag(self, who: Who, tag: Tag) -> Ticket:
        return self._tag(Action.UNFORCE, tag, "UnforceTag")

    def _tag(self, action: Action, tag: Tag, method: str, value: float | None = None) -> Ticket:
        """The station's method of a tag's command (a Null value: none given). A value refused as
        out of the tag's range is said as the station's layer says it, with the range: the
        station decided, the console only words its answer."""
        client = self.client

        def outside() -> str:
            lo, hi = write_range(tag)
            say = words_of(str(client.files.manifest.get("language", "")))
            return say("outside", value=value, lo=tag.format(lo), hi=tag.format(hi))

        args = () if action is Action.UNFORCE else (value,)
        return client.said(client.call(method, tag.name, *args), action, tag.name,
                           out_of_range=None if tag.type is TagType.BIT else outside)


class SharedSession(OpcUaSource):
    """The Program view on the console's own session with the station: closed with the console,
    not with the view. It reads any address: the console watches the whole memory while it is open."""

    def __init__(self, client: ConsoleClient, **listing: Any) -> None:
        super().__init__(client, **listing)
        self.console = client
        self.key = f"program-{id(self):x}"
        client.want(self.key, WHOLE)

    def close(self) -> None:
        self.console.want(self.key, None)


class ConsoleWindow(QMainWindow):
    def __init__(self, source: StationSource, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.source = source
        client = self.client = source.client
        self.setWindowTitle(f"NetPlc console — {client.station or client.url}")
        self.answers = Answers()
        self.answers.answered.connect(self._answered)
        self.target = RemoteTarget(client, self.answers)
        self.commands = StationCommands(client, source.station_alarms)
        self.rights = Rights(self.commands, lambda: self.who)  # type: ignore[arg-type]
        self.views: list[FormView] = []
        self.reads: list[Ranges] = []  # the parts of the memory each view reads
        self.readings: Readings | None = None  # the last given
        self.history: TrendHistory | None = None  # of the forms shown
        self.archive: StationArchiveSource | None = None  # the station's, with its tags as loaded
        self.programs: list[ProgramWindow] = []  # the Program views opened from here
        self.windows: list[QWidget] = []  # the trend windows and viewers opened from here
        self.unacknowledged: list[AlarmRow] = []
        self.faceplates: Faceplates | None = None  # of the forms shown
        frame = station_frame(self, client.station or client.url)
        self.header, self.banner, self.health = frame.header, frame.alarms, frame.health
        self.tabs = frame.tabs
        self.header.login.setVisible(False)  # the console's user is the one it logged in as
        for button in (self.banner.ack, self.banner.ack_all):
            self.rights.add(button, Action.ACKNOWLEDGE, button.text())
        self.journal = JournalDock(RemoteJournal(client), self)
        self.summary = AlarmSummary(source.station_alarms, self.commands,  # type: ignore[arg-type]
                                    lambda: self.who, answers=self.answers)
        self.summary_dock = bottom_docks(self, self.journal, self.summary)
        self.status = QStatusBar()
        self.setStatusBar(self.status)
        station = self.menuBar().addMenu(self.tr("&Station"))
        program = QAction(self.tr("&Program…"), self)  # the listing live, the watch table, forcing
        program.setShortcut(QKeySequence("Ctrl+Shift+P"))
        program.triggered.connect(self.open_program)
        station.addAction(program)
        trends = QAction(self.tr("Run-time &trends…"), self)  # the station's tags, live and archived
        trends.setShortcut(QKeySequence("Ctrl+T"))
        trends.triggered.connect(self.open_trends)
        station.addAction(trends)
        viewer = QAction(self.tr("Open journal &viewer…"), self)  # the station's archive, queried
        viewer.setShortcut(QKeySequence("Ctrl+J"))
        viewer.triggered.connect(self.open_viewer)
        station.addAction(viewer)
        view = self.menuBar().addMenu(self.tr("&View"))
        view.addAction(self.journal.toggleViewAction())
        view.addAction(self.summary_dock.toggleViewAction())
        self.resize(1024, 700)
        self.banner.acknowledged.connect(self.acknowledge)
        self.banner.acknowledged_all.connect(self.summary.acknowledge_all)
        self.summary.changed.connect(self._alarms_changed)
        source.loaded.connect(self._load)
        source.readings.connect(self._on_readings)
        self.tabs.currentChanged.connect(self._shown_changed)
        source.link.connect(self._on_link)
        self._timer = QTimer(self)
        self._timer.timeout.connect(self._tick)
        self._timer.start(STATUS_MS)
        if source.current is not None:
            self._load(source.current)
        self._tick()

    def _load(self, loaded: Loaded) -> None:
        """The station's forms (again, when its files changed), in place of the ones shown."""
        current = self.tabs.currentIndex()
        self.views, self.reads = [], []
        if self.history is not None:
            self.history.close()
            self.history.deleteLater()
        self.archive = StationArchiveSource(self.client, loaded.tags)
        self.history = TrendHistory(ArchiveSeries(self.archive), self)
        while self.tabs.count():
            page = self.tabs.widget(0)
            self.tabs.removeTab(0)
            page.deleteLater()
        for form in loaded.forms:
            view = FormView(form, self.target, user=self.client.user, guard=self._guard)
            self.views.append(view)
            self.reads.append(ranges_of(operands(form.elements)))
            self.history.attach(view)
            self.tabs.addTab(ZoomArea(view), form.title)
        self._faceplates(loaded)
        if loaded.problems:
            self.tabs.addTab(_problems_page(loaded.problems), self.tr("Form problems"))
        if not loaded.forms and not loaded.problems:
            self.tabs.addTab(_placeholder(self.tr("The station serves no forms.")), self.tr("No forms"))
        self.tabs.setCurrentIndex(max(0, min(current, self.tabs.count() - 1)))
        self._shown_changed()

    def _faceplates(self, loaded: Loaded) -> None:
        """The faceplates of the station's tags on these forms, as the workstation's: the station's
        commands (RemoteTarget), its archive, its alarms' states as this console lists them; the
        tag's part of the memory watched while one is open."""
        if self.faceplates is not None:
            self.faceplates.close()
            self.faceplates.deleteLater()
        assert self.archive is not None
        language = str(loaded.files.manifest.get("language", ""))
        defs = alarm_defs(loaded.tags, say=words_of(language))
        console = Console(self.target, lambda: self.who, self.answers,
                          lambda title, text: self.ask(title, text), self.archive, defs, self.summary,
                          watch=self._watch, covers=self._covers)
        self.faceplates = Faceplates(console, loaded.tags.tags, self.views, self)

    def _watch(self, key: str, operand: tuple[int, int] | None) -> None:
        self.client.want(key, None if operand is None else ranges_of([operand]))

    def _covers(self, operand: tuple[int, int]) -> bool:
        """Readings hold the operand: the station's value, or "station unreachable" for all."""
        return bool(self.client.error) or self.source.covered.covers(ranges_of([operand]))

    def open_program(self) -> ProgramWindow | None:
        """Station -> Program: the station's program live, over this console's session, with what
        the user may do there as the station answers (forcing and single scans for an engineer)."""
        loaded = self.source.current
        if loaded is None:
            self.status.showMessage(self.tr("The station's files are not loaded yet"), REFUSAL_MS)
            return None
        source = SharedSession(self.client, program=loaded.program, symbols=loaded.symbols,
                               tags=loaded.tags.by_name)
        window = ProgramWindow(source, lambda: self.client.user)
        window.show()
        self.programs.append(window)
        return window

    def open_trends(self) -> TrendWindow | None:
        """Station -> Run-time trends: the station's tags picked into pens, their history read from
        the station, their live values from this console's readings; the user's named trends kept
        in this console's folder for the station (the console has no archive)."""
        loaded, archive = self.source.current, self.archive
        if loaded is None or archive is None:
            self.status.showMessage(self.tr("The station's files are not loaded yet"), REFUSAL_MS)
            return None
        window = TrendWindow(self.source.readings, loaded.tags.tags, archive, TrendBook(self.client.keep),
                             lambda: self.client.user, self)
        key = f"trends {id(window)}"  # each window its own want, dropped when it closes
        window.watching.connect(lambda tags: self.client.want(
            key, ranges_of(t.operand for t in tags) if tags else None))
        window.show()
        self.windows.append(window)
        return window

    def open_viewer(self) -> ViewerWindow | None:
        """Station -> Open journal viewer: the offline viewer's records and series, read from the
        station's archive (its event and value history) rather than a file."""
        if self.archive is None:
            self.status.showMessage(self.tr("The station's files are not loaded yet"), REFUSAL_MS)
            return None
        symbols = self.source.current.symbols if self.source.current is not None else {}
        window = ViewerWindow(self.archive, symbols={a: n for n, a in symbols.items()})
        window.show()
        self.windows.append(window)
        return window

    def ask(self, title: str, text: str) -> bool:
        """The second step of a command: the operator confirms it (tests answer for them)."""
        return QMessageBox.question(self, title, text) == QMessageBox.StandardButton.Yes

    def _guard(self, element: Writer, what: str) -> str | None:
        """Before a form element writes: its Confirm (the station checks the role when it is sent)."""
        if element.Confirm and not self.ask(self.tr("Confirm"), what + "?"):
            return self.tr("cancelled")
        return None

    def _shown(self) -> tuple[FormView | None, Ranges]:
        """The form view shown and the parts of the memory it reads."""
        i = self.tabs.currentIndex()
        return (self.views[i], self.reads[i]) if 0 <= i < len(self.views) else (None, NOTHING)

    def _shown_changed(self) -> None:
        """Another tab: the console watches what its form reads, and shows it the last readings
        if they cover it already."""
        _, reads = self._shown()
        self.client.want("form", reads)
        if self.readings is not None:
            self._on_readings(self.readings)

    def _on_readings(self, readings: Readings) -> None:
        self.readings = readings
        if self.faceplates is not None:  # each shows the readings that hold its tag
            self.faceplates.show_readings(readings)
        if isinstance(readings, Unreachable):  # every element says so, shown or not
            for view in self.views:
                view.refresh(readings.snapshot, readings)
            return
        view, reads = self._shown()
        if view is not None and self.source.covered.covers(reads):
            view.refresh(readings.snapshot, readings)

    @property
    def who(self) -> Who:
        """The console's user, as the journal at the station names it (the session is who acts)."""
        return Who(self.client.user, Source.OPCUA)

    def _alarms_changed(self) -> None:
        waiting = self.unacknowledged = self.summary.unacknowledged()
        self.banner.show_alarms(waiting)
        self.summary_dock.setWindowTitle(self.tr("Alarms — {0} unacknowledged").format(len(waiting))
                                         if waiting else self.tr("Alarms"))

    def _on_link(self, error: str) -> None:
        self.health.show_problems([self.tr("station unreachable: {0}; reconnecting").format(error)]
                                  if error else [])
        self._tick()

    def _tick(self) -> None:
        self.header.tick()
        where = self.client.where()  # a console of a pair: the station it follows to, and when it did
        if self.header.title.text() != where:
            self.header.title.setText(where)
            self.setWindowTitle(f"NetPlc console — {where}")
        self.header.title.setToolTip(f"{self.client.url}; {self.client.switched}" if self.client.switched
                                     else self.client.url)
        role = words.role(self.client.role) if self.client.role else ""
        self.header.user.setText(f"{self.client.user} ({role})" if role else self.client.user)
        self.rights.update()
        self.summary.rights.update()
        if not self.status.currentMessage():  # a refusal stays its time
            self.status.showMessage(self.client.state(), STATUS_MS + 200)

    def acknowledge(self, alarm: AlarmRow) -> Ticket:
        return self.answers.follow(self.tr("Acknowledge"), self.commands.acknowledge(self.who, alarm.id))

    def _answered(self, what: str, answer: Answer) -> None:
        if not answer.ok:
            self.status.showMessage(self.tr("Refused: ") + words.answer(what, answer), REFUSAL_MS)

    def close_opened(self) -> None:
        """The faceplates, Program views, trend windows and viewers opened from here closed: as the
        console closes, and when a test hands its console to the next test."""
        if self.faceplates is not None:
            self.faceplates.close()
        for window in (*self.programs, *self.windows):
            window.close()
        self.programs.clear()
        self.windows.clear()

    def closeEvent(self, event: QCloseEvent) -> None:
        self._timer.stop()
        self.close_opened()
        self.summary.stop()
        self.journal.close_archive()
        if self.history is not None:
            self.history.close()
        self.source.stop()
        super().closeEvent(event)


def open_console(url: str, user: str | None = None, password: str | None = None,
                 partner: str = "") -> ConsoleWindow | None:
    """Log in to the station at `url` (the login dialog; trust on first use) and open its console;
    None when the login was cancelled, Problems when the station refused it. `partner`: the other
    station of its hot-standby pair, followed to whenever it leads."""
    client = ConsoleClient(url, partner=partner)
    if not logged_in(client, user, password):
        return None
    if client.files is not None:
        i18n.install(application(), str(client.files.manifest.get("language", "")))
    return ConsoleWindow(StationSource(client))


def run_console(url: str, user: str | None = None, partner: str = "") -> int:
    """`python main.py console opc.tcp://... [--user NAME] [--partner URL]` (with --user and stdin
    not a terminal, the password is stdin's first line). Exit 2 when the station refused, 1 when
    cancelled."""
    app = application()
    password = sys.stdin.readline().rstrip("\r\n") if user and not sys.stdin.isatty() else None
    try:
        window = open_console(url, user, password, partner)
    except Problems as e:
        print("\n".join(e.problems), file=sys.stderr)
        return 2
    if window is None:
        return 1
    window.show()
    heap.settle()  # the client, the forms and their widgets live until the console ends
    _quit_on_signals(app)  # Ctrl+C or SIGTERM log out of the station before the console ends
    return app.exec()
