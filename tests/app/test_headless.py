"""`python main.py --no-gui`: the whole station in a process of its own, over real TCP into a real archive."""

from __future__ import annotations

import datetime as dt
import re
import signal
import sqlite3
from pathlib import Path

import pytest

from app.cli import main as cli
from tests.app.conftest import DEMO_NAME
from tests.app.station_fork import Forks


def day_table() -> str:
    return dt.date.today().strftime("%d_%m_%Y")


def kinds(archive: Path) -> dict[str, list[tuple]]:
    con = sqlite3.connect(f"file:{archive}?mode=ro", uri=True)
    try:
        rows = con.execute(f'SELECT kind, grp, type, source, number, value, text FROM "{day_table()}"'
                           " ORDER BY id").fetchall()
    finally:
        con.close()
    out: dict[str, list[tuple]] = {}
    for r in rows:
        out.setdefault(r[0], []).append(r)
    return out


def level_rose(archive: Path) -> bool:
    """The archive holds two NSTOREs of the level, the later higher (committed while it runs)."""
    try:
        level = [r[5] for r in kinds(archive).get("data", []) if (r[1], r[2]) == (1, 1)]
    except sqlite3.Error:  # no archive or no day table yet
        return False
    return len(level) >= 2 and level[-1] > level[0]


def check_archive(archive: Path) -> dict[str, list[tuple]]:
    by_kind = kinds(archive)
    data = by_kind["data"]
    assert {(r[1], r[2]) for r in data} >= {(1, 1), (1, 2), (1, 3), (1, 4), (1, 5)}  # NSTORE group/type
    level = [r[5] for r in data if (r[1], r[2]) == (1, 1)]
    assert level == sorted(level) and level[-1] > level[0]  # the node's level rises after start
    messages = {(r[4], r[6]) for r in by_kind["message"]}
    assert (5, "NetPlc запущен") in messages
    assert (6, "Связь с узлом 0 установлена") in messages
    system = [r[6] for r in by_kind["system"]]
    assert any(t.startswith("станция запускается: ") for t in system)  # the demo speaks Russian
    assert any(t.startswith("станция запущена: NetSyncTime") for t in system)
    assert system[-1] == "станция остановлена"  # the last record written: everything before it is flushed
    assert any(t.startswith("узел 0 (") and t.endswith(": связь есть") for t in system)
    return by_kind


def test_headless_run_for_a_duration(headless_archive: tuple[Path, str]) -> None:
    archive, out = headless_archive
    check_archive(archive)
    lines = out.splitlines()
    assert lines[0].startswith(f"station {DEMO_NAME} started")
    status = [line for line in lines if line.startswith("NetPlc running")]
    assert status and "nodes 1/1 up" in status[-1] and "records" in status[-1]
    assert re.fullmatch(r"station stopped after \d+ scans, \d+ records written", lines[-1]), lines[-1]


def test_a_start_raises_no_quality_alarm_before_the_first_answer(headless_archive: tuple[Path, str]) -> None:
    """The node's link is not up in the first scans: its tags are initial, not comm-fail."""
    alarms = kinds(headless_archive[0]).get("alarm", [])
    assert not [r for r in alarms if r[3].endswith(".BAD")], alarms


def test_sigterm_mid_run_exits_0_with_everything_flushed(demo_copy: Path, station_forks: Forks) -> None:
    """The station as a process of its own (a fork of the worker's, tests/app/station_fork.py),
    stopped with SIGTERM as systemd does."""
    archive = demo_copy / "archive" / "journal.sqlite"
    station = station_forks.start(["--no-gui", str(demo_copy), "--status-every", "0.5"],
                                  demo_copy / "stderr.txt", demo_copy / "stdout.txt")
    try:  # up, and NSTOREs (once a second) in the archive
        station.until(lambda out: "nodes 1/1 up" in out and level_rose(archive))
        station.send_signal(signal.SIGTERM)
        assert station.wait(60) == 0, station.errors()
    finally:
        if station.poll() is None:
            station.kill()
            station.wait(10)
    assert "SIGTERM: stopping" in station.output()
    check_archive(archive)


def test_bad_station_exits_2_naming_the_problem(tmp_path: Path, station_forks: Forks) -> None:
    (tmp_path / "station.toml").write_text('NetPlcProgram = "p.stl"\n', encoding="utf-8")
    (tmp_path / "p.stl").write_text("TNA $09000\nJMP 0\n", encoding="utf-8")
    station = station_forks.start(["--no-gui", str(tmp_path), "--duration", "1"], tmp_path / "stderr.txt")
    assert station.wait(30) == 2
    assert f"{tmp_path / 'p.stl'}:1:5:" in station.errors()


def test_help_everywhere(capsys: pytest.CaptureFixture[str]) -> None:
    for args in ([], ["view"], ["check"], ["simulate"]):
        with pytest.raises(SystemExit) as end:  # `main.py ARGS --help`: what main.py exits with
            cli([*args, "--help"])
        assert end.value.code == 0, (args, capsys.readouterr().err)
        assert "usage:" in capsys.readouterr().out
