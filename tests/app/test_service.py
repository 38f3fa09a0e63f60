"""The headless station under systemd (`Type=notify`): READY=1 after the first scan, WATCHDOG=1 while
the scan goes on and none while it hangs, STATUS= lines, STOPPING=1 at the stop; over a real
datagram socket standing in for the service manager's NOTIFY_SOCKET."""

from __future__ import annotations

import itertools
import os
import signal
import socket
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

from app.station.config import load_station
from app.station.notify import Notifier
from app.station.runtime import Runtime, StartError
from app.station.service import Service
from tests.app.conftest import REPO, write_station
from tests.app.station_fork import Forks

WATCHDOG_USEC = 200_000  # a ping every 0.1 s; the station scans every 20 ms
PROGRAM = "TNA $03760\nCTR C:$03000 N:255\nJMP 0\n"


def tiny_station(folder: Path) -> Path:
    return write_station(folder, 'NetPlcProgram = "count.stl"\nNetSyncTime = 20\n'
                                 "[modbus_server]\nenabled = false\n", {"count.stl": PROGRAM})


class Manager:
    """The service manager's end of NOTIFY_SOCKET: each datagram with the time it came."""

    def __init__(self, address: str) -> None:
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        self.sock.bind("\0" + address[1:] if address.startswith("@") else address)
        self.address = address

    def next(self, timeout: float) -> tuple[float, list[str]] | None:
        """The next notification within `timeout` s, or None."""
        self.sock.settimeout(timeout)
        try:
            data = self.sock.recv(65536)
        except TimeoutError:
            return None
        return time.monotonic(), data.decode().split("\n")

    def until(self, key: str, timeout: float = 10.0) -> list[tuple[float, list[str]]]:
        """Notifications up to and with the first with a line that starts with `key`; AssertionError
        at the deadline."""
        got, deadline = [], time.monotonic() + timeout
        while (left := deadline - time.monotonic()) > 0:
            note = self.next(left)
            if note is not None:
                got.append(note)
                if any(line.startswith(key) for line in note[1]):
                    return got
        raise AssertionError(f"no {key} within {timeout} s: {got}")

    def during(self, seconds: float) -> list[tuple[float, list[str]]]:
        got, deadline = [], time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            note = self.next(left)
            if note is not None:
                got.append(note)
        return got

    def close(self) -> None:
        self.sock.close()


@pytest.fixture
def manager() -> Iterator[Manager]:
    m = Manager(f"@netplc-test-{uuid.uuid4().hex}")  # an abstract address, as systemd's own is
    yield m
    m.close()


def pings(notes: list[tuple[float, list[str]]]) -> list[float]:
    return [t for t, lines in notes if "WATCHDOG=1" in lines]


def test_ready_after_the_first_scan_pings_while_scanning_none_while_hung(tmp_path: Path,
                                                                          manager: Manager) -> None:
    runtime = Runtime(load_station(tiny_station(tmp_path / "station")))
    runtime.start()
    notifier = Notifier({"NOTIFY_SOCKET": manager.address, "WATCHDOG_USEC": str(WATCHDOG_USEC)})
    service = Service(runtime, notifier)
    release, hung = threading.Event(), threading.Event()
    try:
        service.start()
        ready = manager.until("READY=1")[-1][1]
        assert service.scans >= 1
        status = next(line for line in ready if line.startswith("STATUS="))
        assert "NetPlc running" in status and "scans)" in status

        times = pings(manager.during(0.6))
        assert len(times) >= 3
        gaps = sorted(b - a for a, b in itertools.pairwise(times))
        assert gaps[len(gaps) // 2] < WATCHDOG_USEC / 1e6  # every half WATCHDOG_USEC, within the deadline

        def hang(_snapshot: object) -> None:  # a listener that never returns holds the scan thread
            hung.set()
            release.wait()

        assert runtime.engine is not None
        runtime.engine.subscribe(hang, "hang")
        assert hung.wait(5)
        # a ping for the scans before the hang may come first (late under load), then the stall is
        # said; from then on, three periods and more without a ping: systemd would restart the station
        manager.until("STATUS=scan stalled")
        stalled = [note for _ in range(3) for note in manager.until("STATUS=scan stalled")]
        assert pings(stalled) == []

        release.set()
        manager.until("WATCHDOG=1", timeout=2)  # the scan goes on: pings again
    finally:
        release.set()
        service.stopping()
        runtime.stop()
        notifier.close()
    stopping = manager.until("STOPPING=1", timeout=2)
    assert pings(stopping[-1:]) == []


def test_main_no_gui_tells_systemd_ready_watchdog_and_stopping(tmp_path: Path, station_forks: Forks) -> None:
    """The real headless station (`main.py --no-gui` as a process of its own: a fork of the
    worker's, tests/app/station_fork.py): NOTIFY_SOCKET a path, the log on stderr at --log-level
    INFO (the service unit's), SIGTERM as systemd stops it."""
    manager = Manager(str(tmp_path / "notify"))
    station = tiny_station(tmp_path / "station")
    env = {"NOTIFY_SOCKET": manager.address, "WATCHDOG_USEC": str(WATCHDOG_USEC)}
    proc = station_forks.start(["--no-gui", str(station), "--log-level", "INFO", "--status-every", "60"],
                               tmp_path / "stderr.txt", tmp_path / "stdout.txt", env)
    try:
        manager.until("READY=1", timeout=30)
        manager.until("WATCHDOG=1", timeout=2)
        manager.until("WATCHDOG=1", timeout=2)
        proc.send_signal(signal.SIGTERM)
        manager.until("STOPPING=1", timeout=10)
        assert proc.wait(30) == 0, proc.errors()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
        manager.close()
    assert "SIGTERM: stopping" in proc.output()
    assert "INFO MainThread app.station.runtime: station started" in proc.errors()  # the journal gets the log


def test_without_a_service_manager_nothing_is_sent() -> None:
    notifier = Notifier({})
    assert not notifier.enabled and notifier.watchdog is None
    notifier.send("READY=1")  # a no-op, no error
    assert Notifier({"NOTIFY_SOCKET": "@x", "WATCHDOG_USEC": "1000000", "WATCHDOG_PID": "1"}).watchdog is None
    assert Notifier({"NOTIFY_SOCKET": "@x", "WATCHDOG_USEC": "1000000"}).watchdog == 1.0


def test_log_lines_carry_their_priority_for_the_journal(tmp_path: Path) -> None:
    """Under systemd stderr is the journal (JOURNAL_STREAM names it): each line, a traceback's too,
    starts with its syslog priority and leaves the time to the journal."""
    err = tmp_path / "stderr"
    code = ("import logging, os, sys\n"
            "st = os.fstat(2); os.environ['JOURNAL_STREAM'] = f'{st.st_dev}:{st.st_ino}'\n"
            "import app.logs as l; l.configure('INFO')\n"
            "log = logging.getLogger('station')\n"
            "log.info('started'); log.warning('disk slow')\n"
            "try:\n    1 / 0\nexcept ZeroDivisionError:\n    log.exception('scan failed')\n")
    with err.open("w") as f:
        subprocess.run([sys.executable, "-c", code], cwd=REPO, stderr=f, timeout=60, check=True)
    lines = err.read_text().splitlines()
    assert lines[0] == "<6>INFO MainThread station: started"
    assert lines[1] == "<4>WARNING MainThread station: disk slow"
    assert lines[2] == "<3>ERROR MainThread station: scan failed"
    assert lines[-1] == "<3>ZeroDivisionError: division by zero"


def test_a_second_station_on_the_same_folder_is_refused(tmp_path: Path) -> None:
    folder = tiny_station(tmp_path / "station")
    first = Runtime(load_station(folder))
    first.start()
    try:
        with pytest.raises(StartError) as refused:
            Runtime(load_station(folder)).start()
        pid = os.getpid()
        assert refused.value.problems == [f"{folder}: a station is running in this folder (pid {pid}, "
                                          "holding station.lock): stop it first"]
    finally:
        first.stop()
    again = Runtime(load_station(folder))  # the lock goes with the stop
    again.start()
    again.stop()


def test_the_unit_does_not_restart_a_station_whose_configuration_was_refused(tmp_path: Path) -> None:
    """A refused configuration exits 2 (named on stderr); restarting it every RestartSec would only
    repeat the refusal in the journal, so the unit names that status in RestartPreventExitStatus."""
    from app.cli import run_headless

    unit = (REPO / "resources/systemd/netplc-station.service").read_text(encoding="utf-8")
    keys = dict(line.split("=", 1) for line in unit.splitlines() if "=" in line and not line.startswith("#"))
    folder = write_station(tmp_path / "station", 'NetPlcProgram = "missing.stl"\nNetSyncTime = 20\n', {})
    status = run_headless(str(folder), 1, 60)
    assert keys["Restart"] == "on-failure" and keys["RestartPreventExitStatus"] == str(status) == "2"


def test_the_unit_gives_the_station_a_private_cache_folder_it_may_write() -> None:
    """The unit's hardening leaves the service user no home and a read-only OS: the OPC UA server's
    standard address space (app/publish/standard_nodes.py) is kept in the folder systemd makes for
    the unit, private to its user, which is what the station reads a cache file from."""
    from app.publish.standard_nodes import CACHE_ENV

    unit = (REPO / "resources/systemd/netplc-station.service").read_text(encoding="utf-8")
    keys = dict(line.split("=", 1) for line in unit.splitlines() if "=" in line and not line.startswith("#"))
    assert keys["Environment"] == f"{CACHE_ENV}=/var/cache/{keys['CacheDirectory']}"
    assert keys["CacheDirectoryMode"] == "0700" and keys["ProtectHome"] == "yes"
