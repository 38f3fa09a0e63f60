"""The one worker-thread base of the views (hmi_forms/widgets/worker.py): jobs off the GUI thread,
answers on it, failures said and logged, and the thread stopped with its owner."""

from __future__ import annotations

import logging
import sqlite3
import threading

import pytest
import shiboken6
from PySide6.QtCore import QCoreApplication, QObject

from hmi_forms.widgets import worker as worker_module
from hmi_forms.widgets.worker import Worker

WAIT = 10_000


def test_a_job_runs_off_the_gui_thread_and_is_answered_on_it(qtbot) -> None:
    worker = Worker("test", ())
    gui = threading.get_ident()
    answers: list[tuple[int, object, int]] = []
    worker.answered.connect(lambda token, result: answers.append((token, result, threading.get_ident())))
    token = worker.submit(threading.get_ident)
    qtbot.waitUntil(lambda: bool(answers), timeout=WAIT)
    [(answered, job_thread, slot_thread)] = answers
    assert answered == token and job_thread != gui and slot_thread == gui
    worker.close()
    worker.close()  # a second close does nothing
    assert worker.closed
    with pytest.raises(RuntimeError, match="closed"):
        worker.submit(lambda: None)


def test_failures_are_answered_and_logged(qtbot, caplog) -> None:
    worker = Worker("test", (sqlite3.Error,))
    failed: list[tuple[int, str]] = []
    worker.failed.connect(lambda token, why: failed.append((token, why)))

    def gone() -> None:
        raise sqlite3.OperationalError("unable to open database file")

    def bug() -> None:
        raise KeyError("x")

    with caplog.at_level(logging.WARNING, logger="hmi_forms.widgets.worker"):
        first, second = worker.submit(gone), worker.submit(bug)
        qtbot.waitUntil(lambda: len(failed) == 2, timeout=WAIT)
    assert failed == [(first, "unable to open database file"), (second, "KeyError: 'x'")]
    expected, unexpected = caplog.records
    assert expected.levelno == logging.WARNING and expected.exc_info is None  # said, no traceback
    assert unexpected.levelno == logging.ERROR and unexpected.exc_info is not None
    worker.close()


def test_an_expected_failure_that_repeats_is_said_each_time_and_logged_once(qtbot, caplog) -> None:
    """A view that polls (the designer's preview of a station that is down) says every failure, and
    the log has it once until a job succeeds."""
    worker = Worker("poll", (ConnectionError,))
    said: list[str] = []
    worker.failed.connect(lambda _token, why: said.append(why))
    worker.answered.connect(lambda _token, _result: said.append("ok"))

    def down() -> None:
        raise ConnectionRefusedError("station down")

    with caplog.at_level(logging.WARNING, logger="hmi_forms.widgets.worker"):
        for job in (down, down, down, lambda: None, down):
            worker.submit(job)
        qtbot.waitUntil(lambda: len(said) == 5, timeout=WAIT)
    assert said == ["station down"] * 3 + ["ok", "station down"]
    assert [r.getMessage() for r in caplog.records] == ["poll: station down"] * 2  # again after the success
    worker.close()


def test_the_thread_stops_with_its_owner_and_closes_what_it_opened(qtbot) -> None:
    closed = threading.Event()
    owner = QObject()
    worker = Worker("owned", (), owner, on_close=closed.set)
    answers: list[object] = []
    worker.answered.connect(lambda _token, result: answers.append(result))
    worker.submit(lambda: 1)
    qtbot.waitUntil(lambda: answers == [1], timeout=WAIT)
    threads = [t for t in threading.enumerate() if t.name.startswith("owned")]
    assert threads
    shiboken6.delete(owner)  # as a window deletes its children, with no close() called
    assert closed.is_set()
    for t in threads:
        t.join(5)
        assert not t.is_alive()


def test_a_close_waits_for_the_job_under_way_a_bounded_time_and_the_job_ends_on_its_own(
        qtbot, caplog, monkeypatch) -> None:
    """A window that closes during a read that does not end (a station's archive read from a
    console whose station does not answer: up to a minute) waits at most CLOSE_WAIT_S, never for the
    read: the read ends on its own, its answer dropped, the queued jobs never run, and what the
    jobs opened is closed on the worker thread after the read, not under it."""
    monkeypatch.setattr(worker_module, "CLOSE_WAIT_S", 0.05)
    worker = Worker("slow", (), on_close=lambda: closed_after.append(release.is_set()))
    reading, release, closed_after, ran, answers = threading.Event(), threading.Event(), [], [], []
    worker.answered.connect(lambda _token, result: answers.append(result))

    def read() -> str:
        reading.set()
        release.wait(WAIT / 1000)  # the station that does not answer
        return "rows"

    worker.submit(read)
    worker.submit(lambda: ran.append("queued"))
    assert reading.wait(WAIT / 1000)
    with caplog.at_level(logging.WARNING, logger="hmi_forms.widgets.worker"):
        worker.close()
    assert not release.is_set() and not closed_after, "the close waited for the read"
    assert "slow: closed while a job has run for more than 0.05 s" in caplog.text
    threads = [t for t in threading.enumerate() if t.name.startswith("slow")]
    release.set()
    for t in threads:
        t.join(WAIT / 1000)
        assert not t.is_alive()
    assert closed_after == [True] and not ran
    QCoreApplication.processEvents()  # where an answer would arrive
    assert answers == []
