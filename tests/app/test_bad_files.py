"""Broken station files end as named problems (`file:line: ...`), never as tracebacks, hangs or
an OOM: `check` exits 1 listing them, a start exits 2, and the forms that are fine still open.
The stations here are English, as the cases name their problems (test_check.py tries ru). The check
that exits 1 runs as a process of its own (a fork of the worker's, as tests/app/station_fork.py
starts `main.py`); the other commands run in this process (`app.cli.main` and `netplc.cli.main`,
what main.py and `python -m netplc` call, tests/commands.py): a start that exits 2 as a process of
its own is tests/app/test_headless.py's."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

import netplc.cli
from app import cli
from app.station.config import read_station
from app.station.runtime import StartError
from hmi_forms.form import load_forms
from registrar.catalog import Catalog
from tests.app.broken_stations import CASES, Broken, replace
from tests.app.conftest import copy_demo
from tests.app.station_fork import Forks
from tests.commands import run_in_process

NOT_CP1251 = b"\x98"  # a byte that is neither UTF-8 (alone) nor defined in cp1251


@pytest.fixture
def main(capsys: pytest.CaptureFixture[str]) -> Callable[..., subprocess.CompletedProcess[str]]:
    """`python main.py ARGS`, in this process."""
    return lambda *args: run_in_process(cli.main, args, capsys)


def append_line(path: Path, data: bytes) -> int:
    """Append one line of raw bytes; its line number."""
    text = path.read_bytes()
    if not text.endswith(b"\n"):
        text += b"\n"
    path.write_bytes(text + data + b"\n")
    return text.count(b"\n") + 1


def form(elements: list[dict], devices: list[dict] | None = None) -> str:
    return json.dumps({"form": {"title": "t", "width": 200, "height": 200}, "devices": devices or [],
                       "elements": elements})


def bad_forms(folder: Path) -> dict[str, str]:
    """Three forms that used to crash the loader, and the start of the problem each must give."""
    analog = {"type": "AnalogBase", "Name": "Level", "x": 0, "y": 0, "w": 10, "h": 10, "InAddr": "04010",
              "AppMax": 10, "PhyMin": 0, "PhyMax": 1}
    (folder / "x_deep.hmi").write_text('{"form": {"width": 10, "height": 10},\n"elements": '
                                       + "[" * 100_000 + "]" * 100_000 + "}", encoding="utf-8")
    (folder / "x_digits.hmi").write_text(form([]).replace('"width": 200', '"width": ' + "7" * 5000),
                                         encoding="utf-8")
    (folder / "x_appmin.hmi").write_text(form([analog]).replace('"AppMax": 10', '"AppMin": ' + "9" * 400
                                                                + ', "AppMax": 10'), encoding="utf-8")
    return {
        "x_deep.hmi": f"{folder / 'x_deep.hmi'}:2:112: bad JSON: arrays or objects nested too deeply",
        "x_digits.hmi": f"{folder / 'x_digits.hmi'}: form: width: a 5000-digit number is out of range",
        "x_appmin.hmi": f'{folder / "x_appmin.hmi"}: element "Level": AppMin: a 400-digit number is out of '
                        "range",
    }


def test_check_lists_every_bad_file_and_exits_1(tmp_path: Path, station_forks: Forks) -> None:
    st = copy_demo(tmp_path / "st", "en")
    program_line = append_line(st / "netplc.stl", b"; bad " + NOT_CP1251)
    symbols_line = append_line(st / "symbols.csv", b"LONG,02000," + b"x" * 140_000)
    big_line = append_line(st / "messages.csv", f"{2**63},1,0,too big for the archive".encode())
    expected_forms = bad_forms(st / "forms")
    check = station_forks.start(["check", str(st)], tmp_path / "stderr.txt", tmp_path / "stdout.txt")
    assert check.wait(60) == 1, check.output() + check.errors()
    assert "Traceback" not in check.errors()
    out = check.output().splitlines()
    assert f"{st / 'netplc.stl'}:{program_line}:0: neither UTF-8 nor cp1251 text (byte 0x98)" in out
    assert f"{st / 'symbols.csv'}:{symbols_line}:1: a field is longer than 131072 characters" in out
    assert (f"{st / 'messages.csv'}:{big_line}: number {2**63} is past {2**63 - 1}, the largest the archive "
            "holds") in out
    for start in expected_forms.values():
        assert any(line.startswith(start) for line in out), (start, out)


def test_a_station_written_in_cp1251_checks_clean(tmp_path: Path, main) -> None:
    from app.scada.table import load_tags

    st = copy_demo(tmp_path / "st", "en")
    for name in ("netplc.stl", "symbols.csv", "messages.csv", "tags.csv"):
        path = st / name
        path.write_bytes(path.read_text(encoding="utf-8").encode("cp1251"))
    r = main("check", st)
    assert r.returncode == 0, r.stdout + r.stderr
    assert Catalog.load(st / "messages.csv").text_for(1) == "Пуск нажат"
    tag = load_tags(st / "tags.csv", {"LEVEL": 0o4010, "TEMP": 0o4012, "SETPOINT": 0o4030}).get("TEMP")
    assert tag is not None and (tag.description, tag.unit) == ("Температура", "°C")


def test_a_start_with_an_unreadable_symbols_file_exits_2_naming_it(tmp_path: Path, main) -> None:
    st = copy_demo(tmp_path / "st", "en")
    line = append_line(st / "symbols.csv", b"BAD" + NOT_CP1251 + b",02000")
    r = main("--no-gui", st, "--duration", "1")
    assert r.returncode == 2, r.stdout + r.stderr
    assert "Traceback" not in r.stderr
    assert f"{st / 'symbols.csv'}:{line}:0: neither UTF-8 nor cp1251 text (byte 0x98)" in r.stderr


def test_a_start_with_a_message_number_past_int64_exits_2_naming_the_line(tmp_path: Path, main) -> None:
    st = copy_demo(tmp_path / "st", "en")
    line = append_line(st / "messages.csv", f"{2**64},1,0,too big".encode())
    r = main("--no-gui", st, "--duration", "1")
    assert r.returncode == 2, r.stdout + r.stderr
    assert "Traceback" not in r.stderr and f"{st / 'messages.csv'}:{line}: number {2**64} is past" in r.stderr


@pytest.mark.parametrize(("toml", "problem"), [
    ("NetSyncTime = " + "1" * 5000, "not valid TOML: a number of more than 4300 digits"),
    ("NetSyncTime = " + "[" * 5000, "not valid TOML: arrays or tables nested too deeply"),
    ('NetPlcProgram = "a\\u0000b"', "NetPlcProgram: a path cannot hold a NUL character"),
    ('NetPlcLoad = false\n[[nodes]]\nnode = 0\nendpoint = "tcp://127.0.0.1:1"\ntimeout = ' + "9" * 400,
     "nodes[0].timeout: a 400-digit number is too large"),
])
def test_station_files_past_the_toml_reader_limits_are_named(tmp_path: Path, toml: str, problem: str) -> None:
    (tmp_path / "station.toml").write_text(toml, encoding="utf-8")
    assert read_station(tmp_path)[1] == [f"{tmp_path / 'station.toml'}: {problem}"]


def test_a_station_file_in_cp1251_reads(tmp_path: Path) -> None:
    (tmp_path / "station.toml").write_bytes('name = "Насосная"\nNetPlcLoad = false\n'.encode("cp1251"))
    station, problems = read_station(tmp_path)
    assert problems == [] and station is not None and station.name == "Насосная"


def test_netplc_run_names_an_unreadable_program_or_symbols_file(tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    program = tmp_path / "p.stl"
    program.write_bytes(b"TNA $02000 ; \xcf\xf3\xf1\xea\nYON $02001\n")  # a cp1251 comment: fine
    symbols = tmp_path / "s.csv"
    symbols.write_bytes(b"A,02000\nB" + NOT_CP1251 + b",02001\n")
    run = ["run", str(program), "--set", "02000=1", "--print", "02001"]
    r = run_in_process(netplc.cli.main, run, capsys)
    assert r.returncode == 0 and r.stdout == "02001 = 1\n", r.stderr
    r = run_in_process(netplc.cli.main, [*run, "--symbols", str(symbols)], capsys)
    assert r.returncode == 2 and r.stderr == f"{symbols}:2:0: neither UTF-8 nor cp1251 text (byte 0x98)\n"
    program.write_bytes(b"TNA $02000\n" + NOT_CP1251 + b"\n")
    r = run_in_process(netplc.cli.main, run, capsys)
    assert r.returncode == 2 and r.stderr == f"{program}:2:0: neither UTF-8 nor cp1251 text (byte 0x98)\n"


def test_the_good_forms_still_open_beside_the_broken_ones(tmp_path: Path) -> None:
    (tmp_path / "a_good.hmi").write_text(form([{"type": "StaticText", "Name": "T", "x": 0, "y": 0, "w": 10,
                                                "h": 10, "Text": "ok"}]), encoding="utf-8")
    expected = bad_forms(tmp_path)
    forms, problems = load_forms(tmp_path)
    assert [f.path.name for f in forms] == ["a_good.hmi"]
    assert len(problems) == 3
    for start in expected.values():
        assert any(p.startswith(start) for p in problems), (start, problems)


def test_the_workstation_opens_the_demo_forms_beside_the_broken_ones(tmp_path: Path, qtbot) -> None:
    from app.gui.main_window import MainWindow
    from app.station.config import load_station
    from app.station.runtime import Runtime

    st = copy_demo(tmp_path / "st", "en")
    expected = bad_forms(st / "forms")
    runtime = Runtime(load_station(st))
    runtime.start()
    window = MainWindow(runtime)
    qtbot.addWidget(window)
    try:
        titles = [window.tabs.tabText(i) for i in range(window.tabs.count())]
        assert len(window.views) == len(list((st / "forms").glob("0*.hmi"))) == len(titles) - 1
        assert titles[-1] == "Form problems"
        assert all(any(p.startswith(start) for p in window.form_problems) for start in expected.values())
        window.refresh_status()
        assert "form problem: " in window.health.label.text()
    finally:
        window.close()
        runtime.stop()


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_each_bad_input_is_named_by_check_and_by_the_start(tmp_path: Path, case: Broken) -> None:
    from app.station.check import check_station
    from app.station.config import load_station
    from app.station.runtime import Runtime
    from netplc.problems import Problems

    st = copy_demo(tmp_path / "st", "en")
    expected = case.plant(st)
    report = check_station(st)
    assert any(p.startswith(expected) for p in report.problems), (expected, report.problems)
    if case.refused == "load":
        with pytest.raises(Problems) as refused:
            Runtime(load_station(st))
        assert any(p.startswith(expected) for p in refused.value.problems), refused.value.problems
        return
    runtime = Runtime(load_station(st))
    if case.refused == "journal":
        assert any(p.startswith(expected) for p in runtime.form_problems), runtime.form_problems
        return
    with pytest.raises(StartError) as refused:
        runtime.start()
    assert refused.value.problems == [p for p in report.problems if p.startswith(expected)]  # the same words


def test_check_exits_1_naming_a_default_user_who_is_no_viewer_and_a_broken_users_file(tmp_path: Path,
                                                                                     main) -> None:
    st = copy_demo(tmp_path / "st", "en")
    replace(st / "station.toml", 'default_user = "viewer"', 'default_user = "operator"')
    r = main("check", st)
    assert r.returncode == 1 and "Traceback" not in r.stderr
    toml = st / "station.toml"
    assert r.stdout.startswith(f"{toml}: operator.default_user: 'operator' is of role operator: the default")
    (st / "users.json").write_text('{"users": [{"name": "viewer", "role": "viewer"}]}', encoding="utf-8")
    r = main("--no-gui", st, "--duration", "0.5")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stderr == f"{st / 'users.json'}: user 'viewer': salt, hash missing (each a text)\n"


def test_a_station_without_users_may_have_no_default_user(tmp_path: Path) -> None:
    from app.station.check import check_station

    st = copy_demo(tmp_path / "st", "en")
    (st / "users.json").unlink()
    assert check_station(st).problems == [
        f"{st / 'station.toml'}: operator.default_user: no user 'viewer' in {st / 'users.json'} "
        "(`main.py users add viewer --role viewer` adds one)"]
    replace(st / "station.toml", 'default_user = "viewer"', 'default_user = ""')
    assert check_station(st).ok
