"""A Russian pair journals its exchange's and its pair's records in Russian, as its alarms
(tests/app/scada/test_words.py): the link to its node, the start alone, the handover, the
takeover, and `redundancy status` with the time of the last takeover; none of the catalogue's English
words is left."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from app.authority import Source, Who
from app.cli import run_redundancy
from netplc.simulator import Simulator
from tests.app.pair.conftest import Station, make_pair, wait_for, wait_paired
from tests.app.scada.test_words import english_words

ENGINEER = Who("", Source.STATION)


def records(station: Station) -> list[str]:
    """The records of the station and its exchange, the ones the catalogue says."""
    return [r.text for r in station.journal
            if r.kind == "system" and r.text and (r.source == "station" or r.source.startswith("node "))]


def test_a_russian_pair_journals_its_link_and_takeovers_in_russian(
        tmp_path: Path, node: Simulator, capsys: pytest.CaptureFixture[str]) -> None:
    a, b = make_pair(tmp_path, node, top='Language = "ru"\n')
    try:
        a.start()
        b.start()
        wait_paired(a, b)
        assert a.rt.commands is not None and a.rt.commands.into_standby(ENGINEER).result(3).ok
        wait_for(lambda: b.role == "primary" and a.role == "standby", what="switchover")
        wait_for(lambda: any("передано партнёром" in t for t in records(b)), what="the takeover journaled")
        wait_for(lambda: any(t.startswith("узел 1 (") and "связь есть" in t for t in records(b)),
                 what="the new primary's link to the node")
        assert b.rt.pair is not None
        assert run_redundancy(str(b.folder)) == 0
        status = capsys.readouterr().out
    finally:
        for st in (b, a):
            st.stop()
    texts = records(a) + records(b)
    alone = r"пара, станция A: запуск -> основная: партнёр не ответил за \d+ мс от запуска"
    assert any(re.fullmatch(alone, t) for t in texts), texts
    assert "пара, станция A: основная -> резервная: IntoStandBy: station" in texts
    assert "пара, станция B: резервная -> основная: передано партнёром: IntoStandBy: station" in texts
    assert "роль: основная\n" in status and "связь: есть\n" in status, status
    assert re.search(r"последний переход: \d\d\.\d\d\.\d{4} [\d:]{8}: передано партнёром", status), status
    prose = (re.sub(r"\S*[/.:]\S*", "", t) for t in texts)  # paths, files and endpoints are names
    left = {w for t in prose for w in re.findall(r"[A-Za-z]{2,}", t)} & english_words()
    assert not left, f"English words in a Russian pair's records: {sorted(left)}: {texts}"
