"""The parts of cache files (app/publish/standard_nodes.py) that a process cut short left behind:
the next start that writes the cache removes those whose process no longer runs, and says so."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
from pathlib import Path

import pytest

from app.publish import standard_nodes


def gone_pid() -> int:
    """The pid of a process that has run and ended (a station killed while it wrote)."""
    child = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                           capture_output=True, text=True, check=True)
    return int(child.stdout)


def test_the_next_write_of_the_cache_removes_the_parts_of_processes_that_no_longer_run(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    """A part of a dead process goes, of this asyncua's file and of another's; a part of a running
    process (another station writing now) and a file that is no part of ours stay."""
    monkeypatch.setattr(standard_nodes, "fill", dict)  # what the nodes are does not matter here
    path = standard_nodes.cache_file(tmp_path)
    dead, other_dead = gone_pid(), gone_pid()
    left = path.with_name(f"{path.name}.{dead}.part")
    left_by_other_asyncua = tmp_path / f"opcua-standard-1-asyncua-0.9.0-py311.nodes.{other_dead}.part"
    writing = path.with_name(f"{path.name}.{os.getppid()}.part")  # our parent runs
    strangers = [tmp_path / "notes.part", tmp_path / "opcua-standard-x.nodes.part"]
    for part in (left, left_by_other_asyncua, writing, *strangers):
        part.write_bytes(b"half a cache")
    with caplog.at_level(logging.INFO, standard_nodes.__name__):
        standard_nodes._load(tmp_path)
    assert path.exists()
    assert not left.exists() and not left_by_other_asyncua.exists()
    assert writing.exists() and all(p.exists() for p in strangers)
    assert f"{left} removed: the part of a cache file left by process {dead}, which no longer runs" \
        in caplog.text
    assert f"{left_by_other_asyncua} removed" in caplog.text


def test_a_write_that_fails_leaves_no_part(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                           caplog: pytest.LogCaptureFixture) -> None:
    """A full disk (here: a folder where the file would go, so the rename fails) leaves no part of
    the file behind; the server fills as asyncua does and the log says why."""
    monkeypatch.setattr(standard_nodes, "fill", dict)
    standard_nodes.cache_file(tmp_path).mkdir()
    with caplog.at_level(logging.ERROR, standard_nodes.__name__):
        standard_nodes._load(tmp_path)
    assert not list(tmp_path.glob("*.part"))
    assert "the standard address space is not cached" in caplog.text
