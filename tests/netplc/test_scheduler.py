"""ScanThread: scans on its tick in a thread of its own, survives a failing scan, stops cleanly.

These tests use the real monotonic clock (that is what the thread schedules on) but wait on
events with generous timeouts instead of sleeping for fixed times.
"""

from __future__ import annotations

import logging
import threading

from netplc.engine import Engine
from netplc.program import parse
from netplc.scheduler import ScanThread


def engine_for(text: str) -> Engine:
    return Engine(parse(text), tick=0.1)


def test_scans_run_on_the_tick_and_stop():
    engine = engine_for("TNA $03760\nCTR $03000 N:255")
    done = threading.Event()
    engine.subscribe(lambda snap: snap.scan >= 5 and done.set())
    thread = ScanThread(engine, tick=0.005)
    assert engine.tick == 0.005  # overruns are counted against the thread's tick
    thread.start()
    try:
        assert done.wait(10)
        assert thread.running
    finally:
        thread.stop()
    assert not thread.running
    count = engine.scan_counter
    assert count >= 5 and engine.stats.count == count
    assert engine.ctr_values[0o3000] == 1  # the program ran: 03760 rose once, counted
    assert engine.snapshot.scan == count


def test_a_failing_scan_is_reported_and_the_thread_goes_on(caplog):
    engine = engine_for("NOP")
    errors: list[BaseException] = []
    recovered = threading.Event()
    scan = engine.scan

    def faulty_scan():
        snap = scan()
        if snap.scan in (2, 3, 5):
            raise RuntimeError("scan bug")
        if snap.scan >= 6:
            recovered.set()
        return snap

    engine.scan = faulty_scan
    thread = ScanThread(engine, tick=0.005, on_error=errors.append)
    with caplog.at_level(logging.ERROR, logger="netplc.scheduler"):
        thread.start()
        try:
            assert recovered.wait(10)
        finally:
            thread.stop()
    assert [str(e) for e in errors] == ["scan bug"] * 3  # each failed scan is reported...
    # ...and logged with its traceback once, not again at the next scan; again after a good one
    assert [r.exc_info is not None for r in caplog.records] == [True, True]


def test_lock_holds_the_scans_off():
    engine = engine_for("NOP")
    thread = ScanThread(engine, tick=0.002)
    scanned = threading.Event()
    engine.subscribe(lambda snap: scanned.set())
    with thread.lock:
        thread.start()
        before = engine.scan_counter
        assert not scanned.wait(0.05)  # no scan while the lock is held
        assert engine.scan_counter == before
    try:
        assert scanned.wait(10)
    finally:
        thread.stop()
