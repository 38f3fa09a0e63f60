"""The station's log (app/logs.py): one configuration for every command, a rotating file in the
station folder, uncaught exceptions of any thread logged with their traceback."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from app.cli import _log_level
from app.station.config import DEMO_STATION

REPO = Path(__file__).resolve().parents[2]


def test_log_level_is_taken_from_any_place_among_the_arguments():
    assert _log_level(["check", "--log-level", "debug", "st"]) == ("DEBUG", ["check", "st"])
    assert _log_level(["--log-level=error", "--no-gui"]) == ("ERROR", ["--no-gui"])
    assert _log_level([]) == ("WARNING", [])
    with pytest.raises(SystemExit):
        _log_level(["--log-level", "loud"])


def test_a_running_station_logs_into_its_folder(tmp_path):
    station = tmp_path / "st"
    shutil.copytree(DEMO_STATION, station, ignore=shutil.ignore_patterns("archive", "log"))
    r = subprocess.run([sys.executable, "main.py", "--no-gui", str(station), "--duration", "0.5"],
                       cwd=REPO, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    log = (station / "log" / "station.log").read_text(encoding="utf-8")
    assert "station started" in log and "station stopped" in log


def test_a_library_logging_each_request_logs_its_warnings_only_unless_debug():
    code = ("import logging, app.logs as l; l.configure('{}')\n"
            "a = logging.getLogger('asyncua.server.uaprocessor')\n"
            "a.info('Read request'); a.warning('lost')\n")
    quiet = subprocess.run([sys.executable, "-c", code.format("WARNING")], cwd=REPO, capture_output=True,
                           text=True, timeout=60)
    loud = subprocess.run([sys.executable, "-c", code.format("DEBUG")], cwd=REPO, capture_output=True,
                          text=True, timeout=60)
    assert "lost" in quiet.stderr and "Read request" not in quiet.stderr
    assert "Read request" in loud.stderr


def test_an_uncaught_exception_in_a_thread_is_logged_with_its_traceback():
    code = ("import threading, app.logs as l; l.configure('WARNING')\n"
            "t = threading.Thread(target=lambda: 1 / 0, name='worker'); t.start(); t.join()\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert "CRITICAL worker app.logs: uncaught exception in thread worker" in r.stderr
    assert "ZeroDivisionError" in r.stderr
