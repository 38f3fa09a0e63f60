"""The compiled-program cache: used when it holds this program's code for this compiler and Python,
ignored and rebuilt otherwise (another program, damaged file, another Python), never needed."""

from __future__ import annotations

import marshal
from importlib.util import MAGIC_NUMBER
from pathlib import Path
from unittest import mock

import pytest

from netplc import compiler
from netplc.codecache import CodeCache
from netplc.engine import Engine, FakeClock
from netplc.program import parse

TEXT = "TNA $02000\nTIM $03000 N:2\nTNA $03001\nFON C:$03004 N:INCW S:$04002 D:$04000\nYON $02001\nJMP 0\n"


def engine(text: str, cache: Path, **symbols: int) -> Engine:
    return Engine(parse(text, source="p.stl", symbols=symbols), clock=FakeClock(), wallclock=lambda: 0.0,
                  code_cache=cache)


def run(eng: Engine, scans: int = 8) -> tuple:
    assert isinstance(eng.clock, FakeClock)
    eng.mem.set_bit(0o2000, 1)
    for _ in range(scans):
        eng.clock.advance(0.1)
        eng.scan()
    return bytes(eng.mem.bits), bytes(eng.mem.data), eng.held_values()


def files(cache: Path) -> list[Path]:
    return sorted(cache.glob("program-*.code"))


def no_compiling():
    return mock.patch.object(compiler, "generate_source", side_effect=AssertionError("compiled again"))


def test_the_second_start_takes_the_code_from_the_cache(tmp_path: Path) -> None:
    reference = run(Engine(parse(TEXT), clock=FakeClock(), wallclock=lambda: 0.0, compiled=False))
    assert run(engine(TEXT, tmp_path)) == reference
    assert len(files(tmp_path)) == 1
    with no_compiling():
        assert run(engine(TEXT, tmp_path)) == reference


@pytest.mark.parametrize("change", ["text", "symbols", "chunk size"])
def test_another_program_or_compiler_is_compiled_and_replaces_the_file(tmp_path: Path, change: str) -> None:
    text = TEXT.replace("YON $02001", "YON B")  # B from symbols.csv
    engine(text, tmp_path, B=0o2002)
    old = files(tmp_path)
    if change == "text":
        eng = engine(text.replace("N:2", "N:3"), tmp_path, B=0o2002)
    elif change == "symbols":  # the same text, another address
        eng = engine(text, tmp_path, B=0o2003)
    else:
        with mock.patch.object(compiler, "_CHUNK_CONSTS", 3):
            eng = engine(text, tmp_path, B=0o2002)
    assert len(files(tmp_path)) == 1 and files(tmp_path) != old
    run(eng)


@pytest.mark.parametrize("damage", ["truncated", "garbage", "other python", "not code", "empty"])
def test_a_damaged_or_foreign_file_is_ignored_and_rebuilt(tmp_path: Path, damage: str) -> None:
    engine(TEXT, tmp_path)
    (path,) = files(tmp_path)
    data = path.read_bytes()
    header = len(MAGIC_NUMBER) + 32
    path.write_bytes({
        "truncated": data[: len(data) // 2],
        "garbage": data[:header] + b"\xff" * 50,
        "other python": bytes([MAGIC_NUMBER[0] ^ 1]) + data[1:],
        "not code": data[:header] + marshal.dumps({"a": 1}),
        "empty": b"",
    }[damage])
    reference = run(Engine(parse(TEXT), clock=FakeClock(), wallclock=lambda: 0.0, compiled=False))
    assert run(engine(TEXT, tmp_path)) == reference
    assert path.read_bytes() == data  # rebuilt
    with no_compiling():
        engine(TEXT, tmp_path)


def test_a_cache_folder_that_cannot_be_written_only_costs_the_compile(tmp_path: Path) -> None:
    blocked = tmp_path / "file"
    blocked.write_text("not a folder", encoding="utf-8")
    reference = run(Engine(parse(TEXT), clock=FakeClock(), wallclock=lambda: 0.0, compiled=False))
    assert run(engine(TEXT, blocked / "cache")) == reference
    assert CodeCache(blocked / "cache").load(b"\0" * 32) is None


def test_the_key_is_the_same_for_a_parsed_program_and_one_from_the_parse_cache(tmp_path: Path) -> None:
    from netplc.parsecache import ParseCache, parse_file_cached

    (tmp_path / "p.stl").write_text(TEXT, encoding="utf-8")
    cache = ParseCache(tmp_path / "parsed")
    parsed = parse_file_cached(tmp_path / "p.stl", {}, cache)
    loaded = parse_file_cached(tmp_path / "p.stl", {}, cache)  # unmarshalled: shares equal objects
    assert parsed is not loaded and parsed.instrs == loaded.instrs
    eng = Engine(parsed, clock=FakeClock())
    inline, _ = compiler.fon_code(eng)
    assert compiler.program_key(parsed, inline) == compiler.program_key(loaded, inline)
