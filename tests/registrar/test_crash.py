"""Processes killed with SIGKILL: the archive stays intact and retentive memory is not lost."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from netplc.engine import Engine
from netplc.program import parse
from netplc.records import ListSink
from registrar.alarm_state import AlarmStateFile
from registrar.query import Archive
from registrar.retain import Retainer, read_save
from registrar.schema import DAY_GLOB

from . import retain_child

HERE = Path(__file__).parent
ROOT = HERE.parents[1]

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs POSIX signals")


def spawn(script: str, *args: str) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, str(HERE / script), *args], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


def read_until(child: subprocess.Popen[str], done) -> list[str]:
    """Lines the child prints until `done(line)` (the test's timeout guards a stuck child)."""
    assert child.stdout is not None
    lines = []
    for line in child.stdout:
        lines.append(line.split())
        if done(lines[-1]):
            return lines
    raise AssertionError(f"child ended early: {child.stderr.read() if child.stderr else ''}")


def kill(child: subprocess.Popen[str]) -> list[list[str]]:
    child.send_signal(signal.SIGKILL)
    out, _ = child.communicate(timeout=10)
    return [line.split() for line in out.splitlines()]


def test_sigkill_during_writes_keeps_every_committed_record(tmp_path):
    db = tmp_path / "journal.sqlite"
    child = spawn("writer_child.py", str(db))
    try:
        # past its first commits (one every 20 ms), while it writes on: where 30,000 killed it too
        lines = read_until(child, lambda line: int(line[0]) >= 5_000)
        lines += kill(child)
    finally:
        if child.poll() is None:
            child.kill()
    committed = int(lines[-1][0])
    assert committed >= 5_000
    con = sqlite3.connect(db)
    assert con.execute("PRAGMA integrity_check").fetchone() == ("ok",)
    tables = [n for (n,) in con.execute(
        "SELECT name FROM sqlite_master WHERE type = 'table' AND name GLOB ?", (DAY_GLOB,))]
    numbers = set()
    for table in tables:
        numbers.update(n for (n,) in con.execute(f'SELECT number FROM "{table}"'))
    assert set(range(committed)) <= numbers
    with Archive(db) as archive:  # the read side sees the same, straight after the crash
        assert sum(archive.count(day) for day in archive.days()) == len(numbers)


def test_retentive_counting_continues_after_clean_stop_and_sigkill(tmp_path):
    save = tmp_path / "retain.bin"

    child = spawn("retain_child.py", str(save))
    first = read_until(child, lambda line: line[0] == "count" and int(line[1]) >= 30)
    assert first[0][:2] == ["restored", "zeroes"]
    child.send_signal(signal.SIGTERM)
    out, err = child.communicate(timeout=10)
    assert child.returncode == 0, err
    stopped = out.split()
    assert stopped[0] == "stopped"
    word, counter = int(stopped[1]), int(stopped[2])
    assert word >= 30 and counter > 0

    child = spawn("retain_child.py", str(save))
    try:
        lines = read_until(child, lambda line: line[0] == "count" and int(line[1]) >= word + 90)
        assert lines[0] == ["restored", "current", str(word), str(counter)]
        killed_at = time.time()
        lines += kill(child)
    finally:
        if child.poll() is None:
            child.kill()
    last = [line for line in lines if line[0] == "count"][-1]
    killed_word, killed_counter = int(last[1]), int(last[2])
    saved = read_save(save)
    assert killed_at - saved.wall <= 1.25  # saved at least once a second (and a little slack)
    saved_word = int.from_bytes(saved.data[0:2], "little")  # word 04000 is the first data word

    engine = Engine(parse(retain_child.PROGRAM), tick=retain_child.TICK, sink=ListSink())  # the restart,
    restored = ["restored", Retainer(save, engine).restore(),  # as the child restores, in this process
                str(engine.snapshot.get_word(0o4000)), str(engine.ctr_values[0o3000])]
    assert restored[:3] == ["restored", "current", str(saved_word)]
    word_after, counter_after = int(restored[2]), int(restored[3])
    assert word < word_after <= killed_word + 5
    assert killed_word - word_after <= 1.25 / 0.02  # at most about a second of scans behind
    assert counter < counter_after <= killed_counter + 2


def test_sigkill_while_alarm_states_are_saved_leaves_one_whole_round(tmp_path):
    path = tmp_path / "alarms.sqlite"
    child = spawn("alarm_state_child.py", str(path))
    try:
        lines = read_until(child, lambda line: int(line[0]) >= 10)  # saving without pause: killed in one
        lines += kill(child)
    finally:
        if child.poll() is None:
            child.kill()
    saved = int(lines[-1][0])
    states = AlarmStateFile(path).load()
    rounds = {s["round"] for s in states.values()}
    assert len(states) == 200 and len(rounds) == 1  # never half of one round and half of another
    assert rounds.pop() >= saved
