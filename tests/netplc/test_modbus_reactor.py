"""The Modbus servers' thread (netplc/modbus/reactor.py): calls, timers, and a bug that does not
end it. Its sockets are the servers' (test_modbus_server*.py, test_modbus_fuzz.py)."""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterator

import pytest

from netplc.modbus import Reactor


@pytest.fixture
def reactor() -> Iterator[Reactor]:
    r = Reactor("test-reactor")
    r.start()
    try:
        yield r
    finally:
        r.stop()


def test_run_returns_the_result_on_the_thread_and_raises_its_error(reactor: Reactor) -> None:
    assert reactor.run(threading.current_thread).name == "test-reactor"
    with pytest.raises(ZeroDivisionError):
        reactor.run(lambda: 1 // 0)


def test_timers_run_in_order_and_a_cancelled_one_never(reactor: Reactor) -> None:
    done = threading.Event()
    seen: list[str] = []

    def arm() -> None:
        reactor.later(0.02, lambda: (seen.append("late"), done.set()))
        reactor.later(0.01, lambda: seen.append("early")).cancel()
        reactor.later(0.0, lambda: seen.append("now"))
        reactor.soon(lambda: seen.append("soon"))

    reactor.run(arm)
    assert done.wait(10)
    assert seen == ["soon", "now", "late"]


def test_a_failing_call_is_logged_and_the_thread_goes_on(reactor: Reactor,
                                                          caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.ERROR, logger="netplc.modbus.reactor"):
        reactor.call(lambda: [][0])  # type: ignore[misc]
        assert reactor.run(lambda: 42) == 42
    assert "test-reactor: a call failed" in caplog.text
    assert "IndexError" in caplog.text


def test_a_stopped_reactor_takes_no_more_calls() -> None:
    r = Reactor("test-reactor")
    r.start()
    r.stop()
    r.call(lambda: None)  # ignored, not an error
    with pytest.raises(RuntimeError, match="not running"):
        r.run(lambda: None)
