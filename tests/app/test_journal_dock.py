"""The workstation's journal dock over a real archive file: it reads in its worker thread (the GUI
thread never waits for SQLite), and an unreadable archive is said in the dock, not raised."""

from __future__ import annotations

import time
from pathlib import Path

from app.gui.journal import JOURNAL_ROWS, JournalDock
from tests.app.held_archive import Ticks, archive_with, held

WAIT = 10_000  # ms


def dock_on(qtbot, path: Path) -> JournalDock:
    dock = JournalDock(path)
    qtbot.addWidget(dock)
    return dock


def test_the_dock_reads_off_the_gui_thread_while_the_archive_is_locked(qtbot, tmp_path: Path) -> None:
    path = archive_with(tmp_path / "journal.sqlite", [f"m{i}" for i in range(JOURNAL_ROWS + 20)])
    dock = dock_on(qtbot, path)
    ticks = Ticks()
    try:
        with held(path):
            started = time.monotonic()
            dock.refresh()
            assert time.monotonic() - started < 3  # asked, not read (a read would wait 5 s for the lock)
            qtbot.wait(600)
            assert ticks.count >= 5  # the GUI thread ran its timer all the while
            assert dock.model.rowCount() == 0 and dock.summary.text() == ""  # the read is still waiting
        qtbot.waitUntil(lambda: dock.model.rowCount() == JOURNAL_ROWS, timeout=WAIT)
    finally:
        ticks.stop()
    assert dock.summary.text() == f"{JOURNAL_ROWS + 20} records today, newest {JOURNAL_ROWS} shown"
    assert [r.text for r in dock.model.rows[:2]] == [f"m{JOURNAL_ROWS + 19}", f"m{JOURNAL_ROWS + 18}"]
    dock.messages_only.setChecked(False)  # another filter: read again, in the worker too
    qtbot.waitUntil(lambda: dock.summary.text().startswith(f"{JOURNAL_ROWS + 20} records"), timeout=WAIT)
    dock.close_archive()
    assert dock.reader.archive is None  # closed with the worker
    dock.refresh()  # a tick after the close asks nothing


def test_an_unreadable_archive_is_said_in_the_dock(qtbot, tmp_path: Path) -> None:
    path = tmp_path / "journal.sqlite"
    dock = dock_on(qtbot, path)
    dock.refresh()
    qtbot.waitUntil(lambda: dock.summary.text() == "no archive yet", timeout=WAIT)
    path.write_bytes(b"not a database" * 100)
    dock.refresh()
    qtbot.waitUntil(lambda: dock.summary.text().startswith("archive unreadable: "), timeout=WAIT)
    assert dock.model.rowCount() == 0
    dock.refresh()  # and it keeps trying, saying so each time
    qtbot.wait(200)
    assert dock.summary.text().startswith("archive unreadable: ")
    dock.close_archive()
