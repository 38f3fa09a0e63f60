"""Nothing is cut at 1366x768, in Russian (the longer words) as in English: the worst cases of the
console's narrow places, measured with the fonts' metrics against their column or label: the alarm
summary's titles, priorities, states and a shelving note with the longest preset reason; the
demo's journal element (662 px) with its titles, kinds, types and status; a refusal over the
window and a confirmation's title."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from PySide6.QtCore import QCoreApplication, QRect, Qt, QTimer
from PySide6.QtGui import QFont, QFontMetrics
from PySide6.QtWidgets import QApplication, QLabel, QMessageBox, QTableView, QWidget

from app.authority import Commands, Refusal, Source, Who
from app.gui import i18n, words
from app.gui.alarm_summary import SHELVE_REASONS, AlarmSummary
from app.gui.notice import Note, confirm
from app.scada.alarms import State
from app.scada.station import StationAlarms
from hmi_forms.widgets.form_view import FormView
from hmi_forms.widgets.journal import JournalWidget
from netplc.engine import Engine, FakeClock
from netplc.memory import Memory
from netplc.program import parse
from netplc.records import ListSink, Record
from registrar.store import Store
from tests.app.test_alarm_summary import ROLES, TAGS
from tests.hmi_forms.helpers import engine_target
from tests.hmi_forms.test_widgets import engine, one

SCREEN = 1366  # the smallest screen: a dock or a note spans the window's width less its margins


@pytest.fixture(params=["ru", "en"])
def language(request: pytest.FixtureRequest, qapp) -> Iterator[str]:
    assert i18n.install(qapp, request.param) == request.param
    try:
        yield request.param
    finally:
        i18n.uninstall(qapp)


def bold(widget: QWidget) -> QFontMetrics:
    font = QFont(widget.font())
    font.setBold(True)  # the style sheet's titles are bold
    return QFontMetrics(font)


def titles_fit(view: QTableView, columns: range) -> None:
    header, metrics = view.horizontalHeader(), bold(view.horizontalHeader())
    for col in columns:
        title = view.model().headerData(col, Qt.Orientation.Horizontal, Qt.ItemDataRole.DisplayRole)
        assert metrics.horizontalAdvance(title) < header.sectionSize(col), title


def cells_fit(view: QTableView, columns: range) -> None:
    model, metrics = view.model(), view.fontMetrics()
    for row in range(model.rowCount()):
        for col in columns:
            text = model.data(model.index(row, col), Qt.ItemDataRole.DisplayRole)
            assert metrics.horizontalAdvance(text) < view.columnWidth(col), text


def test_the_alarm_summary_shows_titles_states_and_a_shelving_note_whole(qtbot, tmp_path: Path,
                                                                        language: str) -> None:
    (tmp_path / "tags.csv").write_text(TAGS, encoding="utf-8")
    sink = ListSink()
    alarms = StationAlarms(tmp_path / "tags.csv", parse("JMP 0\n"), [], sink, tmp_path / "alarms.sqlite",
                           language=language)
    clock = FakeClock()
    eng = Engine(parse("JMP 0\n"), clock=clock, sink=sink)
    summary = AlarmSummary(alarms, Commands(eng, sink, role_of=ROLES.get, alarms=alarms),
                           lambda: Who("petrov", Source.CONSOLE))
    qtbot.addWidget(summary)
    try:
        mem = Memory()
        mem.set_word(0o4010, 4000)
        mem.set_word(0o4012, 900)
        alarms.on_scan(mem.snapshot(1, 0.0, time.time(), "running"))
        longest = max((QCoreApplication.translate("ShelveDialog", r) for r in SHELVE_REASONS), key=len)
        summary.shelve_alarm("TEMP.H", 480, longest)
        clock.advance(eng.tick)
        eng.scan()
        summary.resize(SCREEN - 20, 220)
        summary.show()
        summary.refresh()
        table = summary.table
        assert [r.state for r in summary.model.rows] == [State.UNACK, State.SHELVED]
        titles_fit(table, range(6))
        cells_fit(table, range(5))
        metrics = table.fontMetrics()
        for text in [words.state(s) for s in State]:  # whichever state comes, it is read whole
            assert metrics.horizontalAdvance(text) < table.columnWidth(3), text
        note = summary.model.data(summary.model.index(1, 5))
        assert longest in note and "petrov" in note
        wrapped = metrics.boundingRect(QRect(0, 0, table.columnWidth(5) - 8, 10_000),
                                       int(Qt.TextFlag.TextWordWrap), note)
        assert table.rowHeight(1) >= wrapped.height(), note  # the shelving note's end is not hidden
    finally:
        alarms.close()


def test_the_journal_element_shows_its_titles_kinds_types_and_status_whole(qtbot, tmp_path: Path,
                                                                          language: str) -> None:
    archive = tmp_path / "archive" / "journal.sqlite"
    store = Store(archive)
    store.start()
    now = time.time()
    for t in range(4):  # info, warning, alarm, critical
        store.put(Record(now, "message", grp=1, type=t, source="LT1", text="Уровень выше 90 %"))
    store.put(Record(now, "operator", source="operator", text="write Пуск (040042): 0 -> 1", value=1.0))
    store.put(Record(now, "system", source="station", text="станция запущена"))
    store.close()
    form = one(tmp_path, "MessageJournal", w=662, h=286, RefreshTicks=1,  # the demo's, at 1:1 at 1366
               Kinds=["message", "operator", "system"])
    view = FormView(form, engine_target(engine()[0]), archive_path=archive)
    qtbot.addWidget(view)
    view.show()
    widget = view.pairs[0][1]
    assert isinstance(widget, JournalWidget)
    try:
        qtbot.waitUntil(lambda: len(widget.table.rows) == 6, timeout=10_000)
        titles_fit(widget.view, range(7))
        cells_fit(widget.view, range(5))  # time, kind, group, type, source
        status = widget.status
        qtbot.waitUntil(lambda: "6" in status.text(), timeout=10_000)  # "6 records", "записей: 6"
        qtbot.waitUntil(lambda: status.fontMetrics().horizontalAdvance(status.text()) <= status.width(),
                        timeout=5_000)  # once laid out, whole
        for child in widget.findChildren(QWidget):  # nothing of the bar squeezed below its least
            if child.isVisible() and child.parent() is widget and child is not widget.view:
                assert child.width() >= child.minimumSizeHint().width(), child
    finally:
        widget.close_archive()


def test_a_refusal_and_a_confirmation_title_are_read_whole(qtbot, language: str) -> None:
    window = QWidget()
    qtbot.addWidget(window)
    window.resize(SCREEN, 700)
    window.show()
    note = Note(window)
    refusal = words.refusal(Refusal("Quit NetPlc Station", "engineer", "operator-on-the-night-shift",
                                    "operator"))
    text = QCoreApplication.translate("MainWindow", "Refused: ") + refusal
    note.say(text, 10_000)
    assert note.height() >= note.heightForWidth(note.width()) > 0  # wrapped to the window, all lines
    seen: list[tuple[int, int]] = []
    title = QCoreApplication.translate("ProgramMonitor", "Unforce all")

    def measure() -> None:
        box = QApplication.activeModalWidget()
        assert isinstance(box, QMessageBox)
        label = next(w for w in box.findChildren(QLabel) if w.text() == f"<b>{title}</b>")
        seen.append((bold(label).horizontalAdvance(title), label.width()))
        box.defaultButton().click()

    QTimer.singleShot(0, measure)
    confirm(window, title, refusal)
    assert seen and seen[0][0] <= seen[0][1], seen
