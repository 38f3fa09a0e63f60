"""A station whose configuration asks for OPC UA, MQTT or the plant archive without its extra
installed is told which extra and how to install it, at `check` and at start; never an ImportError.
A library is made missing the way Python itself knows a module is not there: None in sys.modules."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from app.station.check import check_station
from app.station.config import load_station
from app.station.runtime import Runtime, StartError
from tests.app.conftest import REPO, write_station

PROGRAM = "TNA $03760\nJMP 0\n"


def station(folder: Path, extra_toml: str) -> Path:
    return write_station(folder, f'NetPlcProgram = "p.stl"\n{extra_toml}[modbus_server]\nenabled = false\n',
                         {"p.stl": PROGRAM})


@pytest.mark.parametrize(("toml", "module", "words"), [
    ("[opcua]\nenabled = true\n", "asyncua", "[opcua] needs the extra: pip install 'netplc-station[opcua]' "
                                             "(asyncua is not installed)"),
    ("[mqtt]\nenabled = true\n", "paho.mqtt", "[mqtt] needs the extra: pip install 'netplc-station[mqtt]' "
                                              "(paho.mqtt is not installed)"),
    ('Archive = "postgresql://u@127.0.0.1:1/plant"\n', "psycopg",
     "Archive = postgresql://... (the plant archive) needs the extra: pip install 'netplc-station[postgres]' "
     "(psycopg is not installed)"),
])
def test_check_and_start_name_the_missing_extra(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, toml: str,
                                                module: str, words: str) -> None:
    folder = station(tmp_path / "st", toml)
    monkeypatch.setitem(sys.modules, module, None)
    expected = f"{folder / 'station.toml'}: {words}"
    assert expected in check_station(folder).problems
    with pytest.raises(StartError) as refused:
        Runtime(load_station(folder))
    assert expected in refused.value.problems


def test_installed_extras_are_no_problem(tmp_path: Path) -> None:
    assert check_station(station(tmp_path / "st", "[opcua]\nenabled = true\n")).ok


def test_commands_that_need_an_extra_say_which(tmp_path: Path) -> None:
    code = ("import sys; sys.modules['asyncua'] = None; sys.modules['psycopg'] = None\n"
            "from app.cli import main\n"
            "print(main(['opcua', 'trust', 'st', 'ab']), main(['view', 'postgresql://u@h/plant']))\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=60)
    assert r.stdout.strip() == "2 2", r.stderr
    assert r.stderr.splitlines() == [
        "opcua trust needs the extra: pip install 'netplc-station[opcua]' (asyncua is not installed)",
        "the plant archive needs the extra: pip install 'netplc-station[postgres]' "
        "(psycopg is not installed)"]
