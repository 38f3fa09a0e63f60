"""The MessageJournal element over a real archive file: what it shows, and that it reads the archive
in its worker thread (the GUI thread never waits for SQLite; the newest request wins)."""

from __future__ import annotations

import threading
import time
from pathlib import Path

from hmi_forms.widgets.form_view import FormView
from hmi_forms.widgets.journal import JournalWidget
from netplc.records import Record
from registrar.query import Archive
from registrar.store import Store
from tests.hmi_forms.helpers import engine_target, snap
from tests.hmi_forms.test_widgets import differs, engine, image, one

WAIT = 10_000  # ms: the worker's answer arrives through the GUI thread's event loop


def journal(qtbot, tmp_path: Path, archive: Path, **props) -> tuple[FormView, JournalWidget]:
    form = one(tmp_path, "MessageJournal", w=700, h=240, RefreshTicks=1, **props)
    view = FormView(form, engine_target(engine()[0]), archive_path=archive)
    qtbot.addWidget(view)
    widget = view.pairs[0][1]
    assert isinstance(widget, JournalWidget)
    return view, widget


def texts(widget: JournalWidget) -> list[str | None]:
    return [r.text for r in widget.table.rows]


def test_message_journal_shows_the_archive(qtbot, tmp_path) -> None:
    archive = tmp_path / "archive" / "journal.sqlite"
    view, widget = journal(qtbot, tmp_path, archive)
    qtbot.waitUntil(lambda: widget.status.text() == "no archive yet", timeout=WAIT)
    empty = image(view, qtbot)
    store = Store(archive)
    store.start()
    now = time.time()
    store.put(Record(now, "message", grp=1, type=2, source="LT1", text="Уровень выше 90 %"))
    store.put(Record(now, "message", grp=1, type=0, source="LT1", text="Уровень в норме"))
    store.put(Record(now, "data", source="LT1", value=5.0))
    store.close()
    view.refresh(snap(scan=1))
    qtbot.waitUntil(lambda: texts(widget) == ["Уровень в норме", "Уровень выше 90 %"], timeout=WAIT)
    assert differs(empty, image(view, qtbot)) > 100
    widget.min_type.setCurrentIndex(2)  # alarms and worse
    qtbot.waitUntil(lambda: [r.type for r in widget.table.rows] == [2], timeout=WAIT)
    assert widget.status.text().startswith("1 records")
    widget.close_archive()


def test_message_journal_min_type_takes_alarm_records_by_priority_not_by_state(qtbot, tmp_path) -> None:
    archive = tmp_path / "archive" / "journal.sqlite"
    store = Store(archive)
    store.start()
    now = time.time()
    # an alarm record: grp = priority, type = the new state, number = the old one
    store.put(Record(now, "alarm", grp=1, type=0, source="TEMP.HH", number=2, text="TEMP.HH returned"))
    store.put(Record(now, "alarm", grp=4, type=3, source="TEMP_SP.H", number=1, text="TEMP_SP.H low"))
    store.put(Record(now, "alarm", grp=2, type=1, source="LEVEL.H", number=0, text="LEVEL.H high"))
    store.put(Record(now, "message", grp=1, type=3, text="Авария насоса"))
    store.put(Record(now, "message", grp=1, type=1, text="Связь с узлом 0 потеряна"))
    store.put(Record(now, "data", grp=1, type=3, source="04010", value=5.0))
    store.close()
    _view, widget = journal(qtbot, tmp_path, archive, MinType=2,
                            Kinds=["message", "alarm", "operator", "system", "data"])
    qtbot.waitUntil(lambda: texts(widget) == ["Авария насоса", "LEVEL.H high", "TEMP.HH returned"],
                    timeout=WAIT)
    widget.min_type.setCurrentIndex(3)  # critical: NMSG type 3, alarms of priority 1
    qtbot.waitUntil(lambda: texts(widget) == ["Авария насоса", "TEMP.HH returned"], timeout=WAIT)
    widget.min_type.setCurrentIndex(1)  # warnings and worse: alarms of priority 1-3
    qtbot.waitUntil(lambda: len(widget.table.rows) == 4, timeout=WAIT)
    assert "TEMP_SP.H low" not in texts(widget)
    widget.close_archive()


def test_the_journal_reads_off_the_gui_thread_and_the_newest_request_wins(qtbot, tmp_path,
                                                                         monkeypatch) -> None:
    archive = tmp_path / "archive" / "journal.sqlite"
    store = Store(archive)
    store.start()
    now = time.time()
    for i in range(30):
        store.put(Record(now + i, "message", grp=1, type=i % 3, text=f"m{i}"))
    store.close()
    gui = threading.get_ident()
    gate = threading.Event()  # the archive is slow until the test opens the gate
    reads: list[tuple[int, int | None]] = []  # (thread, the filter's min_type) of each page read
    records = Archive.records

    def slow_records(self, day, flt=None, *args, **kwargs):
        reads.append((threading.get_ident(), flt.min_type if flt else None))
        assert gate.wait(10)
        return records(self, day, flt, *args, **kwargs)

    monkeypatch.setattr(Archive, "records", slow_records)
    view, widget = journal(qtbot, tmp_path, archive, Rows=10)
    answers: list[int] = []
    widget.worker.answered.connect(lambda token, _page: answers.append(token))
    qtbot.waitUntil(lambda: len(reads) == 1, timeout=WAIT)  # the first page: waiting for the disk

    started = time.monotonic()
    widget.min_type.setCurrentIndex(2)  # alarms and worse: queued behind the slow read
    widget.min_type.setCurrentIndex(1)  # warnings and worse: supersedes it
    view.refresh(snap(scan=1))  # a tick: supersedes that, and still owes the new filter's count
    assert time.monotonic() - started < 3  # the GUI thread never waited for the archive (10 s gate)
    assert widget.table.rows == [] and answers == []
    gate.set()
    qtbot.waitUntil(lambda: len(answers) == 1, timeout=WAIT)
    assert [min_type for _thread, min_type in reads] == [None, 1]  # the superseded one never ran
    assert all(thread != gui for thread, _ in reads)
    assert texts(widget) == [f"m{i}" for i in (29, 28, 26, 25, 23, 22, 20, 19, 17, 16)]
    assert widget.status.text().startswith("10 of 20 records")
    qtbot.wait(100)
    assert len(answers) == 1  # the first read's answer was dropped, not shown late
    widget.close_archive()
    assert widget.reader is not None and widget.reader.archive is None  # closed with the worker


def test_an_unreadable_archive_is_said_and_the_view_keeps_running(qtbot, tmp_path) -> None:
    archive = tmp_path / "journal.sqlite"
    archive.write_bytes(b"not a database" * 100)
    view, widget = journal(qtbot, tmp_path, archive)
    qtbot.waitUntil(lambda: widget.status.text().startswith("archive unreadable:"), timeout=WAIT)
    view.refresh(snap(scan=1))
    assert view.errors == []
    widget.close_archive()
    view.refresh(snap(scan=2))  # a tick after the close asks nothing
