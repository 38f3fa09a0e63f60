"""The alarm texts of a station are built in its `Language` (app/scada/words.py): a Russian
station journals its alarms, transitions and notes in Russian with no English word of the
catalogue left, an English one in English; identities and states stay keys."""

from __future__ import annotations

import re

import numpy as np
import pytest

from app.authority.policy import ROLES
from app.scada.alarms import STOPPED_ID, AlarmSystem, State
from app.scada.quality import Quality
from app.scada.station import stop_reason
from app.scada.table import TagAlarms, TagTable
from app.scada.tag import Scaling, Tag, TagType
from app.scada.words import TEXTS, words
from netplc.memory import Memory
from netplc.records import ListSink

LEVEL = Tag("LEVEL", 0o4010, TagType.WORD, "%", Scaling(0, 4095, 0, 100), 1, "Уровень")
T0 = 1_800_000_000.0


def english_words() -> set[str]:
    """The catalogue's English words that its Russian texts do not share (NetPlc, HLT, HH...),
    but the roles' names, which are the names of the tests' users as well."""
    def of(table: dict[str, str]) -> set[str]:
        bare = (re.sub(r"\{[^}]*\}", "", text) for text in table.values())
        return {w for text in bare for w in re.findall(r"[A-Za-z]{2,}", text)}
    return of(TEXTS["en"]) - of(TEXTS["ru"]) - set(ROLES)


def journal(language: str) -> list[str]:
    """Every alarm text and record of a life cycle: raised, acknowledged with a comment, shelved,
    unshelved, out of service and back, bad quality, NetPlc stopped."""
    sink = ListSink()
    table = TagTable([LEVEL], {"LEVEL": TagAlarms(hh=95, h=90, quality_alarm=True, priority=2)})
    now = [T0]
    system = AlarmSystem(table, sink=sink, clock=lambda: now[0], station=True, language=language)
    mem = Memory()
    quality = np.zeros(1, dtype=np.int8)

    def scan(at: float, stopped: str = "") -> None:
        now[0] = T0 + at
        system.evaluate(mem.snapshot(), now[0], quality, (), stopped=stopped)

    mem.set_word(LEVEL.address, int(LEVEL.to_raw(97)))
    scan(1)
    system.acknowledge("LEVEL.HH", "ivanov", comment="seen")
    system.shelve("LEVEL.H", "ivanov", "maintenance", 600, once=True)
    system.unshelve("LEVEL.H", "ivanov")
    system.set_out_of_service("LEVEL.HH", "ivanov", True)
    system.set_out_of_service("LEVEL.HH", "ivanov", False)
    quality[0] = Quality.COMM_FAIL
    scan(2)
    scan(3, stopped=stop_reason("stopped", "engineer", words(language)))
    assert system.get(STOPPED_ID).state is State.UNACK
    return [a.text for a in system.alarms] + [r.text or "" for r in sink.records if r.kind == "alarm"]


def test_a_russian_station_speaks_russian_in_every_alarm_text_and_record() -> None:
    texts = journal("ru")
    english = english_words()
    left = {w for text in texts for w in re.findall(r"[A-Za-z]{2,}", text)} & english
    assert not left, f"English words in Russian alarm texts: {sorted(left)}"
    assert "Уровень: верхний аварийный (HH 95.0 %)" in texts
    assert "Уровень: недостоверное значение" in texts
    assert "NetPlc не работает: остановлена: engineer (код 0)" in texts
    assert any(t.startswith("LEVEL.HH норма -> активна, не квитирована: Уровень") for t in texts)
    assert any("квитирована: seen; оператор ivanov" in t for t in texts)


@pytest.mark.parametrize("language", ["en", ""])  # "" follows the locale: C in the tests
def test_an_english_station_speaks_english(language: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LC_ALL", "C.UTF-8")
    texts = journal(language)
    assert "Уровень: high-high (HH 95.0 %)" in texts and "Уровень: bad quality" in texts
    assert "NetPlc is not running: stopped by engineer (code 0)" in texts
    assert any(t.startswith("LEVEL.HH normal -> active-unacknowledged: Уровень") for t in texts)


def test_every_text_has_both_languages_with_the_same_fields() -> None:
    assert TEXTS["ru"].keys() == TEXTS["en"].keys()
    for key, text in TEXTS["en"].items():
        assert re.findall(r"\{(\w+)", text) == re.findall(r"\{(\w+)", TEXTS["ru"][key]), key
