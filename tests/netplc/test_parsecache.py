"""The parsed-program cache: a start takes the parse of this text, symbols, file and parser from it,
parses again when any of them changed or the file is damaged (said in the log), and keeps the
folder within its bounds; `check` writes none."""

from __future__ import annotations

import hashlib
import logging
import marshal
import os
from pathlib import Path
from unittest import mock

import pytest

from app.station.check import check_station
from app.station.config import load_station
from app.station.load import load
from app.station.runtime import PARSE_CACHE, Runtime
from netplc import parsecache
from netplc.parsecache import ParseCache, parse_file_cached
from netplc.program import ProgramError, parse_file
from tests.app.conftest import write_station

TEXT = "T = $02000\nTNA T\nTIM $03000 N:2\nTNA $03001\nFON C:$03004 N:INCW S:$04002 D:$04000\nYON B\nJMP 0\n"


def files(cache: Path) -> list[Path]:
    return sorted(cache.glob("parsed-*.bin"))


def program(folder: Path, text: str = TEXT, name: str = "p.stl") -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def no_parsing():
    return mock.patch.object(parsecache, "parse", side_effect=AssertionError("parsed again"))


def test_the_second_parse_comes_from_the_cache_and_equals_the_parser(tmp_path: Path) -> None:
    path, cache = program(tmp_path), ParseCache(tmp_path / "cache")
    first = parse_file_cached(path, {"B": 0o2001}, cache)
    assert first == parse_file(path, {"B": 0o2001})
    assert len(files(cache.folder)) == 1
    with no_parsing():
        again = parse_file_cached(path, {"B": 0o2001}, cache)
    assert again == first and again.source == str(path) and again.symbols == {"B": 0o2001, "T": 0o2000}


@pytest.mark.parametrize("change", ["text", "symbols", "file", "parser"])
def test_another_text_symbols_file_or_parser_is_parsed_again(tmp_path: Path, change: str) -> None:
    path, cache = program(tmp_path), ParseCache(tmp_path / "cache")
    parse_file_cached(path, {"B": 0o2001}, cache)
    symbols = {"B": 0o2001}
    if change == "text":
        path.write_text(TEXT.replace("N:2", "N:3"), encoding="utf-8")
    elif change == "symbols":
        symbols = {"B": 0o2002}
    elif change == "file":  # the same text elsewhere: its diagnostics and source name that file
        path = program(tmp_path, name="q.stl")
    calls: list[str] = []
    real = parsecache.parse

    def parse(text: str, **kw):
        calls.append(text)
        return real(text, **kw)

    version = parsecache._parser_version() + (b"#" if change == "parser" else b"")
    with mock.patch.object(parsecache, "parse", parse), \
            mock.patch.object(parsecache, "_parser_version", return_value=version):
        got = parse_file_cached(path, symbols, cache)
    assert calls and got == parse_file(path, symbols)
    assert len(files(cache.folder)) == 2  # both kept: a station has several programs


@pytest.mark.parametrize("damage", ["truncated", "flipped", "empty", "not a program"])
def test_a_damaged_file_is_logged_ignored_and_written_again(tmp_path: Path, damage: str,
                                                            caplog: pytest.LogCaptureFixture) -> None:
    path, cache = program(tmp_path), ParseCache(tmp_path / "cache")
    parse_file_cached(path, {"B": 0o2001}, cache)
    (stored,) = files(cache.folder)
    data = stored.read_bytes()
    key_and_sum = 64
    if damage == "not a program":  # a right checksum over a payload that is not one
        payload = marshal.dumps({"a": 1})
        bad = data[:32] + hashlib.sha256(payload).digest() + payload
    else:
        at = key_and_sum + 10
        bad = {"truncated": data[:len(data) // 2], "empty": b"",
               "flipped": data[:at] + bytes([data[at] ^ 1]) + data[at + 1:]}[damage]
    stored.write_bytes(bad)
    with caplog.at_level(logging.WARNING, logger="netplc.parsecache"):
        got = parse_file_cached(path, {"B": 0o2001}, cache)
    assert got == parse_file(path, {"B": 0o2001})
    assert [r.getMessage() for r in caplog.records if "not used, parsing again" in r.getMessage()]
    assert stored.read_bytes() == data  # rebuilt
    with no_parsing():
        assert parse_file_cached(path, {"B": 0o2001}, cache) == got


def test_the_folder_keeps_the_most_recently_used_within_its_bounds(tmp_path: Path,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(parsecache, "MAX_FILES", 3)
    cache = ParseCache(tmp_path / "cache")
    paths = [program(tmp_path, TEXT.replace("N:2", f"N:{n}"), f"p{n}.stl") for n in range(2, 7)]
    for age, path in enumerate(paths[:3]):
        parse_file_cached(path, {"B": 0o2001}, cache)
        os.utime(_entry(cache, path), (1000 + age, 1000 + age))  # written long ago, in this order
    parse_file_cached(paths[0], {"B": 0o2001}, cache)  # used again: now the newest of the three
    parse_file_cached(paths[3], {"B": 0o2001}, cache)
    assert len(files(cache.folder)) == 3
    assert not _entry(cache, paths[1]).exists()  # the least recently used went
    assert _entry(cache, paths[0]).exists() and _entry(cache, paths[3]).exists()
    size = _entry(cache, paths[3]).stat().st_size
    monkeypatch.setattr(parsecache, "MAX_BYTES", size * 2 + size // 2)  # room for two
    parse_file_cached(paths[4], {"B": 0o2001}, cache)
    assert len(files(cache.folder)) == 2 and _entry(cache, paths[4]).exists()


def _entry(cache: ParseCache, path: Path) -> Path:
    text = path.read_text(encoding="utf-8")
    return cache._path(parsecache.program_key(text, str(path), {"B": 0o2001}))


def test_a_program_with_errors_is_not_kept_and_an_unwritable_folder_costs_the_parse(tmp_path: Path) -> None:
    cache = ParseCache(tmp_path / "cache")
    with pytest.raises(ProgramError, match=r"p\.stl:2:"):
        parse_file_cached(program(tmp_path, "TNA $02000\nXYZ 1\n"), {}, cache)
    assert not cache.folder.exists()
    blocked = tmp_path / "file"
    blocked.write_text("not a folder", encoding="utf-8")
    path = program(tmp_path)
    unwritable = ParseCache(blocked / "cache")
    assert parse_file_cached(path, {"B": 0o2001}, unwritable) == parse_file(path, {"B": 0o2001})


def test_a_start_keeps_its_programs_beside_the_archive_and_check_writes_none(tmp_path: Path) -> None:
    folder = write_station(tmp_path / "st", 'NetPlcProgram = "p.stl"\nSymbols = "symbols.csv"\n',
                           {"p.stl": TEXT, "symbols.csv": "name,address\nB,02001\n"})
    station = load_station(folder)
    assert check_station(folder / "station.toml").ok
    cache = station.Archive.parent / PARSE_CACHE
    assert not cache.exists()
    first = Runtime(station).program  # loaded, not started
    assert len(files(cache)) == 1
    with no_parsing():
        assert load(station, parse_cache=cache).program == first == load(station).program
