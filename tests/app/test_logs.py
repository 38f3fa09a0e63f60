"""The station's log (app/logs.py): one configuration for every command, a rotating file in the
station folder, uncaught exceptions of any thread logged with their traceback."""

from __future__ import annotations

import logging
import threading

import pytest

from app.cli import _log_level, main
from app.logs import configure
from tests.app.conftest import write_station


def test_log_level_is_taken_from_any_place_among_the_arguments():
    assert _log_level(["check", "--log-level", "debug", "st"]) == ("DEBUG", ["check", "st"])
    assert _log_level(["--log-level=error", "--no-gui"]) == ("ERROR", ["--no-gui"])
    assert _log_level([]) == ("WARNING", [])
    with pytest.raises(SystemExit):
        _log_level(["--log-level", "loud"])


def test_a_running_station_logs_into_its_folder(tmp_path):
    station = write_station(tmp_path / "st", 'NetPlcProgram = "p.stl"\n[modbus_server]\nenabled = false\n',
                            {"p.stl": "JMP 0\n"})
    assert main(["--no-gui", str(station), "--duration", "0.1"]) == 0  # `main.py`, in this process
    log = (station / "log" / "station.log").read_text(encoding="utf-8")
    assert "station started" in log and "station stopped" in log


@pytest.fixture
def chatty_level():
    """configure() sets the CHATTY libraries' level: put back as it was for the tests that follow."""
    chatty = logging.getLogger("asyncua")
    level = chatty.level
    yield
    chatty.setLevel(level)


def test_a_library_logging_each_request_logs_its_warnings_only_unless_debug(capsys, chatty_level):
    a = logging.getLogger("asyncua.server.uaprocessor")
    configure("WARNING")
    a.info("Read request")
    a.warning("lost")
    quiet = capsys.readouterr().err
    configure("DEBUG")
    a.info("Read request")
    loud = capsys.readouterr().err
    assert "lost" in quiet and "Read request" not in quiet
    assert "Read request" in loud


def test_an_uncaught_exception_in_a_thread_is_logged_with_its_traceback(capsys):
    configure("WARNING")  # the hooks go with the test (tests/conftest.py)
    t = threading.Thread(target=lambda: 1 / 0, name="worker")
    t.start()
    t.join()
    err = capsys.readouterr().err
    assert "CRITICAL worker app.logs: uncaught exception in thread worker" in err
    assert "ZeroDivisionError" in err
