"""The operator workstation: the station's HMI forms as tabs around a running Runtime.

The window never owns plant state nor station behaviour: memory and its quality come as the
`Readings` of one scan from the station's feed (through the bridge, which may skip scans when the
window lags: only the picture skips), and what the forms do by themselves (sync generators,
element records) the runtime does, window or not.
Every operator action (a form's write, acknowledge, shelve, silence, run, stop, quit, user
administration) is a command of the station's command layer (`runtime.commands`) as the user at
the workstation: the layer checks the role, journals, and answers; the window says a refusal in
the status bar and greys what the user may not use, its tooltip naming the role (app/gui/rights.py).
What is wrong with the station itself (program stopped, node down, archive failing) is shown in
the window, not only logged, because the operator is the one who must act on it.
"""

from __future__ import annotations

import logging
import signal
import sys
from collections.abc import Callable
from dataclasses import dataclass, replace
from importlib import metadata
from typing import TYPE_CHECKING

from PySide6.QtCore import QCoreApplication, QEvent, QObject, QSize, Qt, QTimer
from PySide6.QtGui import QAction, QCloseEvent, QGuiApplication, QKeySequence
from PySide6.QtWidgets import (
    QApplication,
    QDockWidget,
    QLabel,
    QMainWindow,
    QMessageBox,
    QPlainTextEdit,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from app.authority import Action, Answer, Commands, Refusal, Source, Ticket, Who
from app.authority.users import Session, Users
from app.gui import i18n, words
from app.gui.alarm_summary import AlarmSummary
from app.gui.alarms import AlarmBanner, HealthStrip
from app.gui.application import application
from app.gui.bridge import Answers, RuntimeBridge
from app.gui.docks import SMALL_SCREEN, DockStrip
from app.gui.faceplate import Console, Faceplates
from app.gui.header import HeaderLine
from app.gui.journal import JournalDock
from app.gui.login import LoginDialog
from app.gui.navigate import AlarmNavigator
from app.gui.notice import Note, confirm
from app.gui.placement import Placement, primary_size
from app.gui.rights import Rights
from app.gui.status import StationStatusBar, station_problems
from app.gui.trend_history import ArchiveSeries, TrendHistory
from app.gui.users_dialog import UsersDialog
from app.gui.zoom import ACTUAL, FIT_WIDTH, FIT_WINDOW, ZoomArea
from app.scada.alarms import AlarmRow
from app.scada.readings import Readings
from app.scada.trends import TrendBook
from app.scada.words import phrase
from app.station import heap
from app.station.config import load_station
from app.station.runtime import Runtime
from hmi_forms.elements.analog import AnalogOutput
from hmi_forms.elements.base import Writer
from hmi_forms.elements.discrete import DiscreteBase
from hmi_forms.elements.target import EngineTarget
from hmi_forms.widgets.base import ElementWidget
from hmi_forms.widgets.form_view import FormView
from netplc.problems import Problems

if TYPE_CHECKING:
    from app.gui.monitor.window import ProgramWindow

logger = logging.getLogger(__name__)

STATUS_MS = 500
REFUSAL_MS = 10_000
FRAME_HEIGHT = 320  # menu, header line, tabs, journal dock and status bar around a form
MIN_SIZE = (1024, 600)  # the window's minimum fits a 1366x768 screen, whatever the forms hold
JOURNAL_HEIGHT = 190


class MainWindow(QMainWindow):
    def __init__(self, runtime: Runtime, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.runtime = runtime
        station = runtime.station
        self.setWindowTitle(f"NetPlc Station — {station.name}")
        assert runtime.commands is not None, "the runtime is started before its window opens"
        self.commands: Commands = runtime.commands
        self.bridge = RuntimeBridge(runtime, self)
        self.session = Session(Users(station.folder), default=station.operator.default_user,
                               idle=station.operator.idle_logout)
        self.answers = Answers()  # every command's answer, on the GUI thread
        self.target = EngineTarget(self.commands, lambda user: Who(user, Source.CONSOLE),  # the views'
                                   on_answer=self.answers.follow, say=words.answer)
        self.answers.answered.connect(self._answered)
        self.rights = Rights(self.commands, lambda: self.who)
        # the form elements that write, with their own tooltip
        self.writers: dict[ElementWidget, tuple[DiscreteBase | AnalogOutput, str]] = {}
        self.programs: list[ProgramWindow] = []  # the Program views opened from here
        self._quitting = False
        self.views: list[FormView] = []
        self.view_faults: list[str] = []  # form elements that failed to show: logged, in the health strip
        self.history: TrendHistory | None = None
        self.zooms: list[ZoomArea] = []
        # geometry, docks and zoom as kept for this screen size (app/gui/placement.py)
        self.placement = Placement(station.Archive.parent / "workstation.ini", primary_size())
        self.viewers: list[QWidget] = []

        frame = station_frame(self, station.name)
        self.header, self.alarms, self.health = frame.header, frame.alarms, frame.health
        self.tabs, self.note = frame.tabs, frame.note
        self.header.login.clicked.connect(self.log_in_or_out)
        for button in (self.alarms.ack, self.alarms.ack_all):
            self.rights.add(button, Action.ACKNOWLEDGE, button.text())

        self.journal = JournalDock(station.Archive, self)
        self.summary = AlarmSummary(runtime.alarms, self.commands, lambda: self.who, answers=self.answers,
                                    sound=station.alarm_sound, sounds=station.alarm_sounds)
        self.summary_dock = bottom_docks(self, self.journal, self.summary)
        self.dock_strip = DockStrip(self, (self.journal, self.summary_dock), JOURNAL_HEIGHT)
        self.status = StationStatusBar()
        self.setStatusBar(self.status)
        self._build_menu()
        self.form_problems = self._load_forms()
        alarms = runtime.alarms
        self.faceplates = Faceplates(  # a tag's faceplate from any element bound to it
            Console(self.target, lambda: self.who, self.answers, lambda title, text: self.ask(title, text),
                    station.Archive, alarms.system.defs if alarms else (), self.summary),
            alarms.table.tags if alarms else (), self.views, self)
        # a double-click on an alarm shows its tag's element; a tab marks its forms' alarms
        self.navigator = AlarmNavigator(self.tabs, self.zooms, self.faceplates.bound,
                                        alarms.system.defs if alarms else (), self)
        self.navigator.follow(self.summary, self.alarms, self.journal)

        self.bridge.readings.connect(self._on_readings)
        self.summary.changed.connect(self._alarms_changed)
        self.alarms.acknowledged.connect(self._acknowledge)
        self.alarms.acknowledged_all.connect(self.summary.acknowledge_all)
        self._alarms_changed()
        self._timer = QTimer(self)
        self._timer.setInterval(STATUS_MS)
        self._timer.timeout.connect(self.refresh_status)
        self._timer.start()
        self.refresh_status()
        self._fit_to_forms()
        if (collapsed := self.placement.docks_collapsed()) is not None:
            self.dock_strip.set_collapsed(collapsed)
        self._user_changed()
        self._activity = _Activity(self.session, self)

    @property
    def user(self) -> str:
        """The name journaled with what the workstation does ("" while nobody is logged in)."""
        return self.session.name

    @property
    def who(self) -> Who:
        """Who acts from this workstation now, as the command layer knows them."""
        return Who(self.session.name, Source.CONSOLE)

    # --- building ------------------------------------------------------------------------------

    def _build_menu(self) -> None:
        station = self.menuBar().addMenu(self.tr("&Station"))
        # no single key runs or stops the PLC: both ask, and need the engineer role
        self.act_run = QAction(self.tr("&Run NetPlc…"), self)
        self.act_run.triggered.connect(self.run_program)
        self.act_stop = QAction(self.tr("&Stop NetPlc…"), self)
        self.act_stop.triggered.connect(self.stop_program)
        self.act_login = QAction(self.tr("&Log in / switch user…"), self)
        self.act_login.setShortcut(QKeySequence("Ctrl+L"))
        self.act_login.triggered.connect(self.log_in)
        self.act_logout = QAction(self.tr("Log &out"), self)
        self.act_logout.triggered.connect(self.log_out)
        self.act_users = QAction(self.tr("&Users…"), self)
        self.act_users.triggered.connect(self.manage_users)
        program = QAction(self.tr("&Program…"), self)  # the online monitor with forcing (app/gui/monitor/)
        program.setShortcut(QKeySequence("Ctrl+Shift+P"))
        program.triggered.connect(self.open_program)
        viewer = QAction(self.tr("Open journal &viewer…"), self)
        viewer.setShortcut(QKeySequence("Ctrl+J"))
        viewer.triggered.connect(self.open_viewer)
        trends = QAction(self.tr("Run-time &trends…"), self)  # app/gui/trend_window.py
        trends.setShortcut(QKeySequence("Ctrl+T"))
        trends.triggered.connect(self.open_trends)
        self.act_quit = quit_ = QAction(self.tr("&Quit…"), self)
        quit_.setShortcut(QKeySequence("Ctrl+Q"))  # on every platform; it asks before anything stops
        quit_.triggered.connect(self.request_quit)
        station.setToolTipsVisible(True)  # a greyed command says which role it needs
        self._running = True
        self.rights.add(self.act_run, Action.RUN, self.tr("Run NetPlc"), also=lambda: not self._running)
        self.rights.add(self.act_stop, Action.STOP, self.tr("Stop NetPlc"), also=lambda: self._running)
        self.rights.add(self.act_users, Action.USERS, self.tr("Users"))
        self.rights.add(self.act_quit, Action.QUIT, self.tr("Quit"))
        for a in (self.act_run, self.act_stop):
            station.addAction(a)
        station.addSeparator()
        station.addAction(program)
        station.addAction(self.act_login)
        station.addAction(self.act_logout)
        station.addAction(self.act_users)
        station.addSeparator()
        station.addAction(viewer)
        station.addAction(trends)
        for i, sim in enumerate(self.runtime.station.simulators):  # the demo's bad-quality case
            answers = QAction(self.tr("Simulated node {0} answers").format(sim.node), self)
            answers.setCheckable(True)
            answers.setChecked(True)
            answers.setToolTip(
                self.tr("Untick to pull the node's cable: its values go comm-fail, their alarms come"))
            answers.toggled.connect(lambda on, i=i: self.runtime.simulator_answers(i, on))
            station.addAction(answers)
        health = QAction(self.tr("Alarm-system &health…"), self)
        health.triggered.connect(self.open_health)
        station.addAction(health)
        station.addSeparator()
        station.addAction(quit_)
        view = self.menuBar().addMenu(self.tr("&View"))
        view.addAction(self.journal.toggleViewAction())
        view.addAction(self.summary_dock.toggleViewAction())
        full = QAction(self.tr("&Full screen"), self)
        full.setShortcut(QKeySequence("F11"))
        full.triggered.connect(lambda: self.showNormal() if self.isFullScreen() else self.showFullScreen())
        view.addAction(full)
        collapse = QAction(self.tr("&Collapse docks"), self)
        collapse.setShortcut(QKeySequence("F9"))
        collapse.triggered.connect(self.dock_strip.toggle)
        view.addAction(collapse)
        view.addSeparator()
        for text, keys, act in (
                (self.tr("Fit &width"), "Ctrl+1", lambda a: a.set_mode(FIT_WIDTH)),
                (self.tr("Fit &window"), "Ctrl+2", lambda a: a.set_mode(FIT_WINDOW)),
                (self.tr("&100 %"), "Ctrl+0", lambda a: a.set_mode(ACTUAL)),
                (self.tr("Zoom &in"), "Ctrl++", lambda a: a.zoom_by(1)),
                (self.tr("Zoom &out"), "Ctrl+-", lambda a: a.zoom_by(-1))):
            action = QAction(text, self)
            action.setShortcut(QKeySequence(keys))
            action.triggered.connect(lambda _=False, act=act: self._zoom(act))
            view.addAction(action)
        help_ = self.menuBar().addMenu(self.tr("&Help"))
        about = QAction(self.tr("&About"), self)
        about.triggered.connect(self._about)
        help_.addAction(about)

    def _load_forms(self) -> list[str]:
        station = self.runtime.station
        if station.HMIload is None:
            self.tabs.addTab(_placeholder(self.tr("This station has no HMIload folder.")),
                             self.tr("No forms"))
            return []
        forms, problems = self.runtime.open_forms()  # the views' own models: they only show
        self.history = TrendHistory(ArchiveSeries(station.Archive), self)
        for form in forms:
            view = FormView(form, self.target, archive_path=station.Archive, user=self.user,
                            started=self.runtime.started_clock, guard=self._guard,
                            report=self.view_faults.append)
            self.views.append(view)
            self.writers.update({widget: (model, widget.toolTip()) for model, widget in view.pairs
                                 if isinstance(model, (DiscreteBase, AnalogOutput)) and model.Enabled})
            self.history.attach(view)
            area = ZoomArea(view)
            area.restore(self.placement.zoom(form.path))
            area.zoomed.connect(lambda _label, a=area: self._zoomed(a))
            self.zooms.append(area)
            self.tabs.addTab(area, form.title)
        if problems:
            self.tabs.addTab(_problems_page(problems), self.tr("Form problems"))
        if not forms and not problems:
            self.tabs.addTab(_placeholder(self.tr("No .hmi forms in {0}.").format(station.HMIload)),
                             self.tr("No forms"))
        return problems

    def current_zoom(self) -> ZoomArea | None:
        page = self.tabs.currentWidget()
        return page if isinstance(page, ZoomArea) else None

    def _zoom(self, act: Callable[[ZoomArea], None]) -> None:
        area = self.current_zoom()
        if area is not None:
            act(area)

    def _zoomed(self, area: ZoomArea) -> None:
        """Remember the choice for this form, and show it."""
        self.placement.put_zoom(area.form_view.form.path, area.choice)
        if area is self.current_zoom():
            self.status.showMessage(self.tr("Zoom: ") + area.label(), 3000)

    def preferred_size(self) -> QSize:
        """Large enough to show the biggest form above the journal."""
        width = max((v.width() for v in self.views), default=900) + 40
        height = max((v.height() for v in self.views), default=500) + FRAME_HEIGHT
        return QSize(max(width, MIN_SIZE[0]), max(height, MIN_SIZE[1]))

    def _fit_to_forms(self) -> None:
        size = self.preferred_size()
        screen = self.screen()
        if screen is not None:
            size = size.boundedTo(screen.availableGeometry().size())
        self.resize(size)
        self.resizeDocks([self.journal], [JOURNAL_HEIGHT], Qt.Orientation.Vertical)

    # --- live updates --------------------------------------------------------------------------

    def _on_readings(self, readings: Readings) -> None:
        """One scan's memory and the quality of what every element shows, together."""
        for view in self.views:
            view.refresh(readings.snapshot, readings)
        self.faceplates.show_readings(readings)

    def _alarms_changed(self) -> None:
        unacknowledged = self.summary.unacknowledged()
        self.alarms.show_alarms(unacknowledged)
        self.navigator.mark_tabs(unacknowledged)
        self.summary_dock.setWindowTitle(self.tr("Alarms — {0} unacknowledged").format(len(unacknowledged))
                                         if unacknowledged else self.tr("Alarms"))

    def _acknowledge(self, alarm: AlarmRow) -> None:
        self.summary.acknowledge([alarm.id])

    def _user_changed(self) -> None:
        """Operator writes and acknowledgements are commands of the user on duty; what the user
        may not use is greyed (a form's element keeps its look), the role it needs in its tooltip."""
        user = self.user
        for view in self.views:
            for model in view.form.elements:
                model.user = user
        current = self.session.current
        self.header.show_user(current.name if current else "", current.role if current else "",
                              logged_in=self.session.user is not None)
        self.act_logout.setEnabled(self.session.user is not None)
        self._show_rights()

    def _show_rights(self) -> None:
        """Ask the command layer what the user may use now: after a change of user, and with the
        status, so a role changed in users.json shows too."""
        self.rights.update()
        self.summary.rights.update()
        for program in self.programs:
            if program.isVisible():
                program.monitor.update_rights()
        who, said = self.who, dict[str, Refusal | None]()
        for widget, (model, tip) in self.writers.items():
            if model.stale:
                continue  # the quality mark's tooltip is shown; the element's comes back after
            if model.Role not in said:
                said[model.Role] = self.commands.denial(who, Action.WRITE, model.Role)
            why = said[model.Role]
            text = tip if why is None else f"{tip}\n{words.refusal(replace(why, action=model.Name))}"
            if widget.toolTip() != text:
                widget.setToolTip(text)

    def refresh_status(self) -> None:
        status = self.runtime.status()
        self.status.show_status(status)
        self.health.show_problems(station_problems(status) + self.view_faults)
        self._running = status.state == "running"
        self.header.tick()
        if (idle := self.session.idle_expired()) is not None:
            self.runtime.operator(idle.name, "logged out idle")
            self._user_changed()
        else:
            self._show_rights()

    # --- actions -------------------------------------------------------------------------------

    def ask(self, title: str, text: str) -> bool:
        """The second step of a command: the operator confirms it (tests answer for them)."""
        return confirm(self, title, text)

    def _answered(self, what: str, answer: Answer) -> None:
        """A command the layer did not do says why, where the operator looks: the status bar, in
        the console's language."""
        if not answer.ok:
            self.refuse(words.answer(what, answer))

    def refuse(self, text: str) -> None:
        self.status.showMessage(self.tr("Refused: ") + text, REFUSAL_MS)
        self.note.say(self.tr("Refused: ") + text, REFUSAL_MS)  # whole, where the status bar cuts it

    def command(self, action: Action, what: str, send: Callable[[Who], Ticket], question: str = "",
                then: Callable[[Answer], None] | None = None) -> Ticket | None:
        """Send a command as the user on duty; the operator confirms first when there is a
        `question` and the layer would take it (a refused command is refused, not asked)."""
        who = self.who
        if question and self.commands.may(who, action) and not self.ask(what, question):
            return None
        return self.answers.follow(what, send(who), then)

    def _guard(self, element: Writer, what: str) -> str | None:
        """Before a form element writes: its Confirm (the layer checks the role when it is sent)."""
        if element.Confirm and self.commands.may(self.who, Action.WRITE, element.Role) and not self.ask(
                self.tr("Confirm"), what + "?"):
            return self.tr("cancelled")
        return None

    def run_program(self) -> Ticket | None:
        return self.command(Action.RUN, self.tr("Run NetPlc"), self.commands.run, self.tr(
            "Run the NetPlc program? Its chains act on the plant from the next scan."))

    def stop_program(self) -> Ticket | None:
        return self.command(Action.STOP, self.tr("Stop NetPlc"), self.commands.stop, self.tr(
            "Stop the NetPlc program? Exchange, archive and forms keep running, but the program's "
            "chains are no longer executed."))

    def request_quit(self) -> Ticket | None:
        """Quit stops the whole station (soft PLC, exchange, archive): the engineer's, and asked;
        the window closes once the layer has journaled it."""
        return self.command(Action.QUIT, self.tr("Quit"), self.commands.quit, self.tr(
            "Quit NetPlc Station? The NetPlc program, the exchange with the nodes and the archive stop."),
            self._quit)

    def _quit(self, answer: Answer) -> None:
        if answer.ok:
            self._quitting = True
            self.close()

    def log_in(self) -> None:
        LoginDialog(sorted(self.session.users.users), self.login, self).exec()

    def login(self, name: str, password: str) -> None:
        """Log a user in (switching from the one logged in); Refused when the name or password is wrong."""
        before = self.session.user
        user = self.session.login(name, password)
        if before is not None and before is not user:
            self.runtime.operator(before.name, "logged out switched")
        self.runtime.operator(user.name, "logged in", role=phrase(f"role {user.role}"))
        self._user_changed()

    def manage_users(self) -> UsersDialog | None:
        """The users dialog, for whom the layer lets administer users; each change is a command of
        the user on duty, journaled naming them."""
        why = self.commands.denial(self.who, Action.USERS, what=self.tr("Users"))
        if why is not None:
            self.refuse(words.refusal(why))
            return None
        dialog = UsersDialog(self.session.users, self.commands, lambda: self.who, self)
        dialog.show()
        return dialog

    def log_out(self) -> None:
        if self.session.user is not None:
            self.runtime.operator(self.user, "logged out")
            self.session.logout()
            self._user_changed()

    def log_in_or_out(self) -> None:
        if self.session.user is None:
            self.log_in()
        else:
            self.log_out()


    def open_program(self) -> None:
        """Station -> Program: the listing live, the watch table, forcing, single scans."""
        from app.gui.monitor.window import open_local

        window = open_local(self.runtime, lambda: self.user)
        self.viewers.append(window)
        self.programs.append(window)

    def open_viewer(self) -> None:
        from app.gui.viewer import ViewerWindow

        viewer = ViewerWindow(self.runtime.station.Archive)
        viewer.show()
        self.viewers.append(viewer)

    def open_trends(self) -> QWidget:
        from app.gui.trend_window import TrendWindow

        alarms = self.runtime.alarms
        archive = self.runtime.station.Archive
        window = TrendWindow(self.bridge.readings, alarms.table.tags if alarms else (), archive,
                             TrendBook(archive.parent), lambda: self.user, self)  # a window of its own
        window.show()
        self.viewers.append(window)
        return window

    def open_health(self) -> None:
        from app.gui.alarm_health import HealthDialog

        HealthDialog(self.runtime.station.Archive, self).exec()

    def about_text(self) -> str:
        return (self.tr("NetPlc Station {0}: the PC runtime for CPU-165 PLC networks (FregatServer).")
                .format(version()) + "\n" + self.tr("Station: {0}").format(self.runtime.station.path))

    def _about(self) -> None:
        QMessageBox.about(self, "NetPlc Station", self.about_text())

    def closeEvent(self, event: QCloseEvent) -> None:
        """The window manager's close button is Quit; a close from the program (SIGTERM, Ctrl+C,
        tests) closes at once, flushing the archive."""
        if event.spontaneous() and not self._quitting:
            self.request_quit()  # closes the window once the layer has answered
            event.ignore()
            return
        self._activity.stop()
        self.placement.put_docks_collapsed(self.dock_strip.collapsed)
        self.placement.save(self)  # written now, with the zoom choices kept since the last write
        for view in self.views:  # the guards refer back to the window: no cycle left for the GC
            for model in view.form.elements:
                if isinstance(model, Writer):
                    model.guard = None
        self._timer.stop()
        self.faceplates.close()
        self.summary.stop()
        self.bridge.detach()
        self.journal.close_archive()
        if self.history is not None:
            self.history.close()
        for viewer in self.viewers:
            viewer.close()
        super().closeEvent(event)


@dataclass
class Frame:
    """What the workstation and a remote console (app/gui/console/) show around the forms: the
    one header line (station, alarm banner, health strip, user, clock), the forms' tabs, and the
    note that shows a refusal whole over them."""

    header: HeaderLine
    alarms: AlarmBanner
    health: HealthStrip
    tabs: QTabWidget
    note: Note


def bottom_docks(window: QMainWindow, journal: JournalDock, summary: AlarmSummary) -> QDockWidget:
    """The journal and the alarm summary docked below the forms, tabbed, the summary on top; its dock."""
    window.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, journal)
    dock = QDockWidget(QCoreApplication.translate("MainWindow", "Alarms"), window)
    dock.setObjectName("alarmSummaryDock")
    dock.setWidget(summary)
    window.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, dock)
    window.tabifyDockWidget(journal, dock)
    dock.raise_()
    return dock


def station_frame(window: QMainWindow, title: str) -> Frame:
    """The frame as `window`'s central widget."""
    central = QWidget()
    central.setObjectName("central")
    lay = QVBoxLayout(central)
    lay.setContentsMargins(0, 0, 0, 0)
    lay.setSpacing(0)
    alarms, health = AlarmBanner(), HealthStrip()
    # station, alarm banner, health strip, user and clock: one line of a fixed height
    header = HeaderLine(title, alarms, health,
                        QCoreApplication.translate("MainWindow", "No unacknowledged alarms"))
    tabs = QTabWidget()
    tabs.setObjectName("forms")
    tabs.setDocumentMode(True)
    lay.addWidget(header)
    lay.addWidget(tabs, 1)
    window.setCentralWidget(central)
    return Frame(header, alarms, health, tabs, Note(central))


class _Activity(QObject):
    """Any key, click or wheel in the application keeps the user logged in: the idle logout
    counts from the last one.

    The application's windows are watched (QWindow: a key, click or wheel reaches the window before
    its widgets), not the application: a filter on the application is called in Python for every
    event of every widget (paints, timers, layouts), a tenth of a busy workstation's time. A window
    is watched from the moment one of them takes the focus, as a new window does when shown and a
    click does in any other."""

    INPUT = (QEvent.Type.KeyPress, QEvent.Type.MouseButtonPress, QEvent.Type.Wheel)

    def __init__(self, session: Session, parent: QObject) -> None:
        super().__init__(parent)
        self.session = session
        self.app = QApplication.instance()
        if isinstance(self.app, QGuiApplication):
            self.app.focusWindowChanged.connect(self._watch)
            self._watch()

    def _watch(self, *_: object) -> None:
        for window in QGuiApplication.topLevelWindows():
            window.installEventFilter(self)  # once: installing again only moves it to the front

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if event.type() in self.INPUT:
            self.session.touch()
        return False

    def stop(self) -> None:
        if isinstance(self.app, QGuiApplication):
            self.app.focusWindowChanged.disconnect(self._watch)
            for window in QGuiApplication.topLevelWindows():
                window.removeEventFilter(self)
        self.app = None


def version() -> str:
    """The installed package's version (pyproject.toml), or "dev" when run from a bare checkout."""
    try:
        return metadata.version("netplc-station")
    except metadata.PackageNotFoundError:
        return "dev"


def _problems_page(problems: list[str]) -> QWidget:
    """Each problem in full, wrapped: a long path must not widen the window."""
    text = QPlainTextEdit("Forms that could not be opened:\n\n" + "\n".join(problems))
    text.setReadOnly(True)
    text.setLineWrapMode(QPlainTextEdit.LineWrapMode.WidgetWidth)
    return text


def _placeholder(text: str) -> QWidget:
    label = QLabel(text)
    label.setAlignment(Qt.AlignmentFlag.AlignCenter)
    label.setWordWrap(True)
    label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
    return label


def run_workstation(station_path: str, fullscreen: bool = False) -> int:
    """`python main.py [STATION] [--fullscreen]`: start the runtime, show the window (full screen
    in the operator mode, else as kept for this screen size, maximized the first time), stop the
    runtime on close."""
    app = application()
    try:
        station = load_station(station_path)
        i18n.install(app, station.Language)
        runtime = Runtime(station)
        runtime.start()
    except Problems as e:
        print("\n".join(e.problems), file=sys.stderr)
        QMessageBox.critical(None, "NetPlc Station", "The station cannot start:\n\n" + "\n".join(e.problems))
        return 2
    except OSError as e:
        print(f"the station cannot start: {e}", file=sys.stderr)
        QMessageBox.critical(None, "NetPlc Station", f"The station cannot start:\n\n{e}")
        return 2
    window = MainWindow(runtime)
    window.placement.show(window, fullscreen or station.operator.fullscreen)
    screen = window.screen()
    if window.placement.docks_collapsed() is None and screen is not None \
            and screen.size().height() < SMALL_SCREEN:
        window.dock_strip.set_collapsed(True)  # the first start on a small screen: the picture first
    heap.settle()  # the runtime, the forms and their widgets live until the stop: no collection walks them
    _quit_on_signals(app)
    try:
        return app.exec()
    finally:
        runtime.stop()


def _quit_on_signals(app: QApplication) -> None:
    """Ctrl+C or SIGTERM close the window like Quit does, so the archive is flushed. Python runs
    signal handlers only between bytecodes, so a timer lets the interpreter in while Qt waits."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: app.closeAllWindows())
    timer = QTimer(app)
    timer.timeout.connect(lambda: None)
    timer.start(250)

