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
    QFrame,
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QMessageBox,
    QPlainTextEdit,
    QScrollArea,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from app.config import load_station
from app.gui.alarms import Alarm, AlarmBanner, FixedLine, HealthStrip
from app.gui.bridge import RuntimeBridge
from app.gui.journal import JournalDock
from app.gui.status import StationStatusBar, station_problems
from app.gui.style import apply_style
from app.runtime import Runtime
from hmi_forms.elements.target import EngineTarget
from hmi_forms.widgets.form_view import FormView
from netplc.memory import Snapshot
from netplc.problems import Problems
from netplc.records import Record

STATUS_MS = 500
FRAME_HEIGHT = 380  # menu, header, banner, tabs, journal dock and status bar around a form
MIN_SIZE = (1024, 600)  # the window's minimum fits a 1366x768 screen, whatever the forms hold
ALARM_LINE, HEALTH_LINE = 40, 28  # the header's fixed lines: their content changes, never their size
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
        lay.addWidget(FixedLine(self.alarms, self.tr("No unacknowledged alarms"), ALARM_LINE))
        lay.addWidget(FixedLine(self.health, "", HEALTH_LINE))
        lay.addWidget(self.tabs, 1)
        self.setCentralWidget(central)

        self.journal = JournalDock(station.Archive, self)
        self.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, self.journal)
        self.status = StationStatusBar()
        self.setStatusBar(self.status)
        self._build_menu()
        self.form_problems = self._load_forms()

        self.bridge.snapshot.connect(self._on_snapshot)
        self.bridge.record.connect(self._on_record)
        self.alarms.acknowledged.connect(self._acknowledge)
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
        viewer = QAction("Open journal &viewer…", self)
        viewer.setShortcut(QKeySequence("Ctrl+J"))
        viewer.triggered.connect(self.open_viewer)
        quit_ = QAction("&Quit", self)
        quit_.setShortcut(QKeySequence.StandardKey.Quit)
        quit_.triggered.connect(self.close)
        for a in (self.act_run, self.act_stop):
            station.addAction(a)
        station.addSeparator()
        station.addAction(viewer)
        station.addSeparator()
        station.addAction(quit_)
        view = self.menuBar().addMenu("&View")
        view.addAction(self.journal.toggleViewAction())
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
        target = EngineTarget(self.runtime.engine)
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
            self.tabs.addTab(_problems_page(problems), "Form problems")
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
        for view in self.views:
            view.refresh(snapshot)

    def _on_record(self, record: Record) -> None:
        if record.kind == "message":
            self.alarms.add(record, self.runtime.message_text(record))

    def _acknowledge(self, alarm: Alarm) -> None:
        self.runtime.acknowledge(alarm.record, self.user)

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

    def open_viewer(self) -> None:
        from app.gui.viewer import ViewerWindow

        viewer = ViewerWindow(self.runtime.station.Archive)
        viewer.show()
        self.viewers.append(viewer)

    def _about(self) -> None:
        QMessageBox.about(self, "NetPlc Station",
                          "NetPlc Station: the PC runtime for CPU-165 PLC networks (FregatServer).\n"
                          f"Station: {self.runtime.station.path}")

    def closeEvent(self, event: QCloseEvent) -> None:
        self._timer.stop()
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

