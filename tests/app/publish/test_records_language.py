"""A Russian station journals what its operators did and what it did itself in Russian, as it does
its alarms (tests/app/scada/test_words.py) and its pair's records (tests/app/pair/test_language.py):
the writes, the forces, the refusals and the answers a person reads, the registrar's own records, the
start records of OPC UA and MQTT, a login; none of the catalogue's English words is left. Without a
`Language`, under the C locale, the same records stay English: the tests of the commands and the
protocols read them so, on an English copy of the demo (`copy_demo(..., "en")`)."""

from __future__ import annotations

import re
from pathlib import Path

from app.authority import Reason, Source, Who
from app.scada.words import phrase
from app.station.runtime import Runtime
from netplc.records import Record
from tests.app.publish.conftest import Mosquitto, demo_with, free_port, mqtt_section
from tests.app.scada.test_words import english_words
from tests.netplc.test_exchange import wait_until

ENGINEER = Who("engineer", Source.CONSOLE)
VIEWER = Who("viewer", Source.CONSOLE)


def act(station: Runtime) -> list[str]:
    commands = station.commands
    assert commands is not None
    assert commands.write_tag(ENGINEER, "TEMP_SP", 100).result(10).ok
    assert commands.write_bit(ENGINEER, 0o2000, 1, label="Пуск").result(10).ok
    assert commands.force_tag(ENGINEER, "TEMP_SP", 90).result(10).ok
    assert commands.force_tag(ENGINEER, "TEMP_SP").result(10).ok  # bumpless, over its own force
    assert commands.unforce_tag(ENGINEER, "TEMP_SP").result(10).ok
    assert commands.force(ENGINEER, "bit", 0o2001, 1).result(10).ok
    assert commands.unforce_all(ENGINEER).result(10).ok
    refused = [commands.write_tag(VIEWER, "TEMP_SP", 50).result(10),
               commands.write_tag(ENGINEER, "TEMP_SP", 1000).result(10),
               commands.write_tag(ENGINEER, "NO_SUCH", 1).result(10),
               commands.shelve(ENGINEER, "LEVEL.H", "", 60).result(10),
               commands.step(ENGINEER, None).result(10)]
    assert [a.reason for a in refused] == [Reason.DENIED, Reason.OUT_OF_RANGE, Reason.UNKNOWN, Reason.INVALID,
                                           Reason.NOT_RUNNING]
    station.operator("engineer", "logged in", role=phrase("role engineer"))
    assert station.engine is not None
    last = station.engine.scan_counter
    wait_until(lambda: station.engine is not None and station.engine.scan_counter > last + 2)
    return [a.text for a in refused]


def test_a_russian_station_journals_its_commands_and_its_own_records_in_russian(tmp_path: Path,
                                                                              broker: Mosquitto) -> None:
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    records: list[Record] = []
    opcua = f'[opcua]\nenabled = true\nendpoint = "{url}"\n'
    station = demo_with(tmp_path / "station", f"{opcua}\n{mqtt_section(broker)}", records)  # the demo's ru
    try:
        answers = act(station)
    finally:
        station.stop()
    texts = [r.text for r in records if r.kind in ("system", "operator") and r.text]
    write = r"запись Уставка температуры TEMP_SP: [-\d.]+ -> 100\.0 °C \(код \d+ -> 3071 по адресу \d+\)"
    assert any(re.fullmatch(write, t) for t in texts), texts
    assert "запись Пуск (02000): 0 -> 1" in texts, texts
    assert any(re.fullmatch(r"фиксация TEMP_SP: [-\d.]+ -> 90\.0 °C \(код \w+\)", t) for t in texts), texts
    assert any(re.fullmatch(r"фиксация TEMP_SP: зафиксировано 90\.0 -> 90\.0 °C \(код \w+\) \(безударно\)", t)
               for t in texts), texts
    assert "снятие фиксации TEMP_SP (было зафиксировано 90.0 °C)" in texts, texts
    # 02001 is the demo's sync generator output (SYNC_OUT), pulsing once 02000 (SYNC_SELECT) is 1 above
    assert any(re.fullmatch(r"фиксация 02001: [01] -> 1", t) for t in texts), texts
    assert "снятие фиксации 02001 (было зафиксировано 1; снять все)" in texts
    assert "отказ: запись TEMP_SP: нужна роль «оператор»; viewer — наблюдатель" in texts, texts
    assert answers[0] == "нужна роль «оператор»; viewer — наблюдатель"
    assert answers[1] == "1000 вне диапазона -50.0 °C .. 150.0 °C", answers
    assert answers[2:] == ["нет тега 'NO_SUCH'", "LEVEL.H: для откладывания нужна причина",
                           "станция не запущена"]
    assert "вход, роль «инженер»" in texts
    restored = "сохраняемая память начинается с нулей (текущее сохранение отсутствует; предыдущее сохранение"
    assert any(t.startswith(restored) for t in texts), texts
    assert any(t.startswith("сервер OPC UA на opc.tcp://") for t in texts), texts
    assert any(t.startswith("публикация MQTT Sparkplug B на ") for t in texts), texts
    prose = (re.sub(r"\S*[/.:]\S*", "", t) for t in texts)  # paths, files, addresses and endpoints are names
    left = {w for t in prose for w in re.findall(r"[A-Za-z]{2,}", t)} & english_words()
    assert not left, f"English words in a Russian station's records: {sorted(left)}: {texts}"

