"""The operator workstation: the station's HMI forms as tabs around a running Runtime.

The window never owns plant state nor station behaviour: memory comes as snapshots from the scan
thread (through the bridge, which may skip snapshots when the window lags: only the picture
skips), operator actions go to the engine's queued writes, and what the forms do by themselves
(sync generators, element records) the runtime does, window or not.
What is wrong with the station itself (program stopped, node down, archive failing) is shown in
the window, not only logged, because the operator is the one who must act on it.
"""

from __future__ import annotations

import signal
import sys
import time

from PySide6.QtCore import QSize, Qt, QTimer
from PySide6.QtGui import QAction, QCloseEvent, QKeySequence
from PySide6.QtWidgets import (
    QApplication,
    QComboBox,
    QDockWidget,
    QFrame,
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QMessageBox,
    QScrollArea,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from app.config import load_station
from app.gui.alarm_summary import AlarmSummary
from app.gui.alarms import AlarmBanner, HealthStrip
from app.gui.bridge import RuntimeBridge
from app.gui.journal import JournalDock
from app.gui.status import StationStatusBar, station_problems
from app.gui.style import apply_style
from app.runtime import Runtime
from hmi_forms.elements.target import EngineTarget
from hmi_forms.widgets.form_view import FormView
from netplc.memory import Snapshot
from netplc.problems import Problems
from netplc.tags.alarms import AlarmRow

STATUS_MS = 500
FRAME_HEIGHT = 380  # menu, header, banner, tabs, journal dock and status bar around a form
MIN_SIZE = (1024, 720)
JOURNAL_HEIGHT = 190


class MainWindow(QMainWindow):
    def __init__(self, runtime: Runtime, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.runtime = runtime
        station = runtime.station
        self.setWindowTitle(f"NetPlc Station — {station.name}")
        self.bridge = RuntimeBridge(runtime, self)
        self.views: list[FormView] = []
        self.viewers: list[QWidget] = []

        central = QWidget()
        central.setObjectName("central")
        lay = QVBoxLayout(central)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        self.header = _Header(station.name, station.users)
        self.alarms = AlarmBanner()
        self.health = HealthStrip()
        self.tabs = QTabWidget()
        self.tabs.setObjectName("forms")
        self.tabs.setDocumentMode(True)
        lay.addWidget(self.header)
        lay.addWidget(self.alarms)
        lay.addWidget(self.health)
        lay.addWidget(self.tabs, 1)
        self.setCentralWidget(central)

        self.journal = JournalDock(station.Archive, self)
        self.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, self.journal)
        self.summary = AlarmSummary(runtime.alarms, lambda: self.user, sound=station.alarm_sound)
        self.summary_dock = QDockWidget("Alarms", self)
        self.summary_dock.setObjectName("alarmSummaryDock")
        self.summary_dock.setWidget(self.summary)
        self.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, self.summary_dock)
        self.tabifyDockWidget(self.journal, self.summary_dock)
        self.summary_dock.raise_()
        self.status = StationStatusBar()
        self.setStatusBar(self.status)
        self._build_menu()
        self.form_problems = self._load_forms()

        self.bridge.snapshot.connect(self._on_snapshot)
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

    @property
    def user(self) -> str:
        return self.header.user.currentText()

    # --- building ------------------------------------------------------------------------------

    def _build_menu(self) -> None:
        station = self.menuBar().addMenu("&Station")
        self.act_run = QAction("&Run NetPlc", self)
        self.act_run.setShortcut(QKeySequence("F5"))
        self.act_run.triggered.connect(self.runtime.run_program)
        self.act_stop = QAction("&Stop NetPlc", self)
        self.act_stop.setShortcut(QKeySequence("Shift+F5"))
        self.act_stop.triggered.connect(self._confirm_stop)
        program = QAction("&Program…", self)  # the online monitor with forcing (app/gui/monitor/)
        program.setShortcut(QKeySequence("Ctrl+Shift+P"))
        program.triggered.connect(self.open_program)
        viewer = QAction("Open journal &viewer…", self)
        viewer.setShortcut(QKeySequence("Ctrl+J"))
        viewer.triggered.connect(self.open_viewer)
        quit_ = QAction("&Quit", self)
        quit_.setShortcut(QKeySequence.StandardKey.Quit)
        quit_.triggered.connect(self.close)
        for a in (self.act_run, self.act_stop):
            station.addAction(a)
        station.addSeparator()
        station.addAction(program)
        station.addAction(viewer)
        for i, sim in enumerate(self.runtime.station.simulators):  # the demo's bad-quality case
            answers = QAction(f"Simulated node {sim.node} answers", self)
            answers.setCheckable(True)
            answers.setChecked(True)
            answers.setToolTip("Untick to pull the node's cable: its values go comm-fail, their alarms come")
            answers.toggled.connect(lambda on, i=i: self.runtime.simulator_answers(i, on))
            station.addAction(answers)
        health = QAction("Alarm-system &health…", self)
        health.triggered.connect(self.open_health)
        station.addAction(health)
        station.addSeparator()
        station.addAction(quit_)
        view = self.menuBar().addMenu("&View")
        view.addAction(self.journal.toggleViewAction())
        view.addAction(self.summary_dock.toggleViewAction())
        help_ = self.menuBar().addMenu("&Help")
        about = QAction("&About", self)
        about.triggered.connect(self._about)
        help_.addAction(about)

    def _load_forms(self) -> list[str]:
        station = self.runtime.station
        if station.HMIload is None:
            self.tabs.addTab(_placeholder("This station has no HMIload folder."), "No forms")
            return []
        forms, problems = self.runtime.open_forms()  # the views' own models: they only show
        target = EngineTarget(self.runtime.engine, self.runtime.tags)
        for form in forms:
            view = FormView(form, target, archive_path=station.Archive, user=self.user,
                            started=self.runtime.started_clock)
            self.views.append(view)
            scroll = QScrollArea()
            scroll.setWidget(view)
            scroll.setAlignment(Qt.AlignmentFlag.AlignHCenter | Qt.AlignmentFlag.AlignTop)
            scroll.setFrameShape(QFrame.Shape.NoFrame)
            self.tabs.addTab(scroll, form.title)
        if problems:
            self.tabs.addTab(_placeholder("Form problems (a form with a wrong property does not open; "
                                          "one naming a file outside the station opens without it):\n\n"
                                          + "\n".join(problems)),
                             "Form problems")
        if not forms and not problems:
            self.tabs.addTab(_placeholder(f"No .hmi forms in {station.HMIload}."), "No forms")
        self.header.user.currentTextChanged.connect(self._user_changed)
        return problems

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

    def _on_snapshot(self, snapshot: Snapshot) -> None:
        readings = self.runtime.readings()  # the quality of what every element shows
        for view in self.views:
            view.refresh(snapshot, readings)

    def _alarms_changed(self) -> None:
        unacknowledged = self.summary.unacknowledged()
        self.alarms.show_alarms(unacknowledged)
        self.summary_dock.setWindowTitle(f"Alarms — {len(unacknowledged)} unacknowledged"
                                         if unacknowledged else "Alarms")

    def _acknowledge(self, alarm: AlarmRow) -> None:
        self.summary.acknowledge([alarm.id])

    def _user_changed(self, user: str) -> None:
        """Operator writes and acknowledgements are journaled under the operator on duty."""
        for view in self.views:
            for model in view.form.elements:
                model.user = user

    def refresh_status(self) -> None:
        status = self.runtime.status()
        self.status.show_status(status)
        problems = station_problems(status)
        self.health.show_problems(problems)
        running = status.state == "running"
        self.act_run.setEnabled(not running)
        self.act_stop.setEnabled(running)
        self.header.tick()

    # --- actions -------------------------------------------------------------------------------

    def _confirm_stop(self) -> None:
        answer = QMessageBox.question(self, "Stop NetPlc",
                                      "Stop the NetPlc program? Exchange, archive and forms keep running, "
                                      "but the program's chains are no longer executed.")
        if answer == QMessageBox.StandardButton.Yes:
            self.runtime.stop_program()

    def open_program(self) -> None:
        """Station -> Program: the listing live, the watch table, forcing, single scans."""
        from app.gui.monitor.window import may_open_program, open_local

        if not may_open_program(self.runtime.station, self.user):
            QMessageBox.warning(
                self, "Program", f"{self.user} may not open the program view (role engineer).")
            return
        self.viewers.append(open_local(self.runtime, lambda: self.user))

    def open_viewer(self) -> None:
        from app.gui.viewer import ViewerWindow

        viewer = ViewerWindow(self.runtime.station.Archive)
        viewer.show()
        self.viewers.append(viewer)

    def open_health(self) -> None:
        from app.gui.alarm_health import HealthDialog

        HealthDialog(self.runtime.station.Archive, self).exec()

    def _about(self) -> None:
        QMessageBox.about(self, "NetPlc Station",
                          "NetPlc Station: the PC runtime for CPU-165 PLC networks (FregatServer).\n"
                          f"Station: {self.runtime.station.path}")

    def closeEvent(self, event: QCloseEvent) -> None:
        self._timer.stop()
        self.summary.stop()
        self.bridge.detach()
        self.journal.close_archive()
        for viewer in self.viewers:
            viewer.close()
        super().closeEvent(event)


class _Header(QFrame):
    """Station name, operator on duty, date and time: the strip every SCADA screen starts with."""

    def __init__(self, name: str, users: tuple[str, ...]) -> None:
        super().__init__()
        self.setObjectName("header")
        lay = QHBoxLayout(self)
        lay.setContentsMargins(14, 6, 14, 6)
        title = QLabel(name)
        title.setObjectName("headerTitle")
        product = QLabel("NetPlc Station")
        product.setObjectName("headerProduct")
        self.user = QComboBox()
        self.user.setObjectName("headerUser")
        self.user.addItems(list(users))
        self.clock = QLabel()
        self.clock.setObjectName("headerClock")
        lay.addWidget(product)
        lay.addWidget(title)
        lay.addStretch(1)
        who = QLabel("Operator:")
        who.setObjectName("headerLabel")
        lay.addWidget(who)
        lay.addWidget(self.user)
        lay.addSpacing(18)
        lay.addWidget(self.clock)
        self.tick()

    def tick(self) -> None:
        self.clock.setText(time.strftime("%d.%m.%Y  %H:%M:%S"))


def _placeholder(text: str) -> QWidget:
    label = QLabel(text)
    label.setAlignment(Qt.AlignmentFlag.AlignCenter)
    label.setWordWrap(True)
    label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
    return label


def run_workstation(station_path: str) -> int:
    """`python main.py [STATION]`: start the runtime, show the window, stop the runtime on close."""
    app = QApplication.instance() or QApplication(sys.argv[:1])
    apply_style(app)
    try:
        runtime = Runtime(load_station(station_path))
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
    window.show()
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

