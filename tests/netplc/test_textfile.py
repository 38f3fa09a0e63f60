"""The one reader of station text files: only a regular file, at most MAX_BYTES, inside the station
folder where asked; everything else a TextFileError naming the file, never a hang or an OOM."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import pytest

from netplc.textfile import MAX_BYTES, TextFileError, confine, csv_rows, file_problem, read_text, resolve
from netplc.words import english, phrase


def problem(path: Path, **kw: int) -> str:
    with pytest.raises(TextFileError) as e:
        read_text(path, "read form", **kw)
    assert e.value.source == str(path)
    return str(e.value)


def test_only_a_regular_file_is_read(tmp_path: Path) -> None:
    (tmp_path / "folder").mkdir()
    os.mkfifo(tmp_path / "fifo")
    os.symlink("/dev/zero", tmp_path / "zero")
    os.symlink("loop", tmp_path / "loop")
    os.symlink("nowhere", tmp_path / "dangling")
    assert problem(tmp_path / "folder") == (f"{tmp_path / 'folder'}: cannot read the form: it is a "
                                            "folder, not a file")
    assert problem(tmp_path / "zero") == (f"{tmp_path / 'zero'}: cannot read the form: it is a character "
                                          "device, not a file")
    assert problem(tmp_path / "loop").endswith("cannot read the form: Too many levels of symbolic links")
    assert problem(tmp_path / "dangling").endswith("cannot read the form: No such file or directory")
    fifo: list[str] = []
    reader = threading.Thread(target=lambda: fifo.append(problem(tmp_path / "fifo")), daemon=True)
    reader.start()
    reader.join(5)  # opening a FIFO no one writes to blocks, unless opened non-blocking
    assert fifo == [f"{tmp_path / 'fifo'}: cannot read the form: it is a FIFO (named pipe), not a file"]
    assert file_problem(tmp_path / "fifo") == "is a FIFO (named pipe), not a file"
    assert file_problem(tmp_path / "folder", folder=True) is None
    assert file_problem(tmp_path / "nothing") == "does not exist"


def test_a_file_past_the_limit_is_not_read(tmp_path: Path) -> None:
    path = tmp_path / "big.stl"
    path.write_bytes(b"NOP\n" * 100)
    assert read_text(path, limit=400) == "NOP\n" * 100
    assert problem(path, limit=399) == (f"{path}: cannot read the form: larger than 0 MB, the most a "
                                        "station file may hold")
    with path.open("r+b") as f:
        f.truncate(MAX_BYTES + 1)  # sparse
    assert problem(path).endswith("larger than 16 MB, the most a station file may hold")


def test_links_are_followed_and_a_loop_or_an_escape_is_named(tmp_path: Path) -> None:
    station = tmp_path / "station"
    station.mkdir()
    (station / "in.hmi").write_text("{}", encoding="utf-8")
    os.symlink("in.hmi", station / "alias.hmi")
    os.symlink("/etc/hostname", station / "out.hmi")
    os.symlink("loop.hmi", station / "loop.hmi")
    assert confine(station / "alias.hmi", station) == station / "in.hmi"
    with pytest.raises(TextFileError) as e:
        confine(station / "out.hmi", station)
    assert str(e.value) == (f"{station / 'out.hmi'}: /etc/hostname is outside the station folder {station} "
                            "(allow_outside = true permits it)")
    with pytest.raises(TextFileError, match=r"loop\.hmi: a loop of symbolic links"):
        resolve(station / "loop.hmi")


def test_a_csv_row_is_one_line() -> None:
    assert list(csv_rows('A,1\n"B\nC",2\nD,3\n')) == [
        (1, ["A", "1"]),
        (2, phrase("csv runs on", line=3)),
        (4, ["D", "3"])]
    assert english("csv runs on", line=3) == ("a quoted field runs on to line 3: a row is one line "
                                              "(a closing quote missing?)")
