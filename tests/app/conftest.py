"""Stations for the application tests: copies of the demo station and small hand-made ones."""

from __future__ import annotations

import signal
import subprocess
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from app.gui.screenshots import copy_station
from app.station.config import DEMO_STATION
from tests.app.station_fork import Forks
from tests.cheap_users import cheap_demo_users

REPO = Path(__file__).resolve().parents[2]
DEMO = DEMO_STATION
DEMO_NAME = "Демо-станция"  # the demo's `name` in its station.toml


def copy_demo(dest: Path, language: str | None = None) -> Path:
    """The demo station copied to `dest`, its archive there too, its Modbus server on a free port;
    in `language` when given ("" follows the locale: English under the tests' C locale), else in
    the demo's (ru). The tests of a protocol or a command that read its records word for word take
    an English copy; the demo's Russian is tested where the language is the point. Its users
    are hashed at the tests' cheap cost (tests/cheap_users.py), their passwords the demo's."""
    copy_station(dest)
    cheap_demo_users(dest)
    toml = dest / "station.toml"
    text = toml.read_text(encoding="utf-8")
    assert "\nport = 0\n" in text and '\nLanguage = "ru"' in text
    if language is not None:
        toml.write_text(text.replace('\nLanguage = "ru"', f'\nLanguage = "{language}"'), encoding="utf-8")
    return dest


def stop_once_up(proc: subprocess.Popen[str], settle: float = 0.0,
                 until: Callable[[], bool] | None = None) -> tuple[str, str]:
    """Wait (at most 30 s) for a `--no-gui` station's status line with its node up, let it run
    `settle` s more or until `until()` holds, then stop it with SIGTERM as systemd does: its whole
    output (killed if it hangs, its threads' stacks in the error where PYTHONFAULTHANDLER is set)."""
    seen: list[str] = []
    try:
        assert proc.stdout is not None
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            seen.append(proc.stdout.readline())
            if not seen[-1] or "nodes 1/1 up" in seen[-1]:  # up, or the station ended
                break
        time.sleep(settle)
        while until is not None and time.monotonic() < deadline and not until():
            time.sleep(0.05)
        proc.send_signal(signal.SIGTERM)
        try:
            out, err = proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:  # with PYTHONFAULTHANDLER set, SIGABRT prints every stack
            proc.send_signal(signal.SIGABRT)
            out, err = proc.communicate(timeout=10)
            said = "".join(seen) + out + err
            raise AssertionError(f"the station did not stop on SIGTERM:\n{said}") from None
        return "".join(seen) + out, err
    finally:
        if proc.poll() is None:
            proc.kill()


def write_station(folder: Path, toml: str, files: dict[str, str] | None = None) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "station.toml").write_text(toml, encoding="utf-8")
    for name, text in (files or {}).items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(text, encoding="utf-8")
    return folder


@pytest.fixture(scope="session")
def station_forks(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Forks]:
    """The worker's forking process (tests/app/station_fork.py): a test that needs a station as a
    process of its own (signals, exit codes, SIGKILL) starts it as a fork of this one, which has
    imported the station once, instead of a `python main.py` that imports it again."""
    forks = Forks(tmp_path_factory.mktemp("forks") / "stderr.txt")
    yield forks
    forks.close()


@pytest.fixture
def demo_copy(tmp_path: Path) -> Path:
    return copy_demo(tmp_path / "station")


@pytest.fixture(scope="session")
def headless_archive(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """The demo station run headless for 5 s, once per run: its archive and its output. Under xdist
    the first worker to need it runs it and the others wait for it and read what it left (the
    tests only read the archive)."""
    import fcntl
    import os
    import shutil
    import subprocess
    import sys

    shared = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        shared = shared.parent  # the run's folder, above each worker's own
    folder, out = shared / "headless", shared / "headless" / "stdout.txt"
    with open(shared / "headless.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when closed
        if not out.exists():
            shutil.rmtree(folder, ignore_errors=True)  # what a failed run of another worker left
            station = copy_demo(folder / "station")
            r = subprocess.run([sys.executable, "main.py", "--no-gui", str(station), "--duration", "5",
                                "--status-every", "1"], cwd=REPO, capture_output=True, text=True, timeout=60)
            assert r.returncode == 0, r.stderr
            out.write_text(r.stdout, encoding="utf-8")
    return folder / "station" / "archive" / "journal.sqlite", out.read_text(encoding="utf-8")
