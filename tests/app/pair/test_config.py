"""[redundancy] in station.toml and `check` of a pair: what must differ between A and B, and what
must not (issue 26, slice 1)."""

from __future__ import annotations

import shutil
from pathlib import Path

from app.station.check import check_pair, check_station
from app.station.config import read_station
from tests.app.conftest import write_station

PAIR = """\
name = "pair"
NetPlcProgram = "p.stl"
NetSyncTime = 50
[modbus_server]
enabled = false
[redundancy]
letter = "{letter}"
listen = "127.0.0.1:{listen}"
partner = "127.0.0.1:{partner}"
"""


def pair_station(folder: Path, letter: str, listen: int = 0, partner: int = 1) -> Path:
    return write_station(folder, PAIR.format(letter=letter, listen=listen, partner=partner),
                         {"p.stl": "TNA $03760\nCTR C:$03000 N:255\nJMP 0\n"})


def test_redundancy_keys_are_read_with_their_defaults(tmp_path: Path) -> None:
    station, problems = read_station(pair_station(tmp_path / "a", "A", 7001, 7002))
    assert problems == [] and station is not None and station.redundancy is not None
    pair = station.redundancy
    assert (pair.letter, pair.listen_address, pair.partner_address) == ("A", ("127.0.0.1", 7001),
                                                                        ("127.0.0.1", 7002))
    assert (pair.failover_after, pair.arbiter) == (10, "none")  # the ticks of 0.5 s (NetSyncTime 50)


def test_bad_redundancy_keys_are_named(tmp_path: Path) -> None:
    folder = write_station(tmp_path / "a", """\
NetPlcProgram = "p.stl"
NetSyncTime = 100
[redundancy]
letter = "C"
partner = "nowhere"
failover_after = 50
arbiter = "mysql://x"
colour = 1
""", {"p.stl": "JMP 0\n"})
    _station, problems = read_station(folder)
    text = "\n".join(problems)
    for key in ("letter: 'C' is not A or B", "partner: 'nowhere' is not HOST:PORT",
                "failover_after: 50 is outside 2-10", "redundancy.arbiter", "redundancy.colour: unknown"):
        assert key in text, text


def test_check_warns_of_a_pair_without_an_arbiter(tmp_path: Path) -> None:
    report = check_station(pair_station(tmp_path / "a", "A"))
    assert report.ok, report.problems
    assert any("arbiter" in w and "split brain" in w for w in report.warnings)


def test_check_of_a_pair_names_the_files_that_differ(tmp_path: Path) -> None:
    a = pair_station(tmp_path / "a", "A", 7001, 7002)
    b = pair_station(tmp_path / "b", "B", 7002, 7001)
    report = check_pair(a, b)
    assert report.ok, report.problems  # letter, listen and partner may differ, nothing else
    (b / "p.stl").write_text("JMP 0\n", encoding="utf-8")
    (b / "station.toml").write_text((b / "station.toml").read_text().replace("50", "60"))
    report = check_pair(a, b)
    assert any("p.stl, station.toml differ" in p for p in report.problems), report.problems
    for folder in (a, b):  # no name: each is named by its folder, a and b
        toml = folder / "station.toml"
        toml.write_text(toml.read_text().replace('name = "pair"\n', ""))
    assert any("the station's name" in p for p in check_pair(a, b).problems)


def test_a_pair_of_one_letter_is_refused(tmp_path: Path) -> None:
    a = pair_station(tmp_path / "a", "A")
    b = tmp_path / "b"
    shutil.copytree(a, b)
    report = check_pair(a, b)
    assert any("both stations are A" in p for p in report.problems), report.problems
