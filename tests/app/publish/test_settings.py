"""[opcua] and [mqtt] in station.toml, the published points and the write rules, without a network."""

from __future__ import annotations

import asyncio
from pathlib import Path

import numpy as np
import pytest

from app.config import load_station, read_station
from app.publish.opcua import station_certificate
from app.publish.points import MAX_PENDING_WRITES, Writable, Writer, WriteRefused, symbol_tags
from app.publish.sparkplug import DOUBLE, INT16, Payload, get_value, set_value
from netplc.engine import Engine
from netplc.program import parse
from netplc.records import ListSink
from netplc.tags.tag import Scaling, Tag, TagType
from tests.app.conftest import write_station

PROGRAM = {"p.stl": "JMP 0\n"}


def test_defaults_are_off_loopback_and_read_only(tmp_path: Path) -> None:
    st = load_station(write_station(tmp_path, 'NetPlcProgram = "p.stl"\n', PROGRAM))
    assert not st.opcua.enabled and st.opcua.endpoint == "opc.tcp://127.0.0.1:4840/netplc/"
    assert st.opcua.writable == () and st.mqtt.writable == ()
    assert not st.mqtt.enabled and st.mqtt.edge_node_id == ""


def test_settings_read_and_every_problem_named(tmp_path: Path) -> None:
    write_station(tmp_path, '''NetPlcProgram = "p.stl"
[opcua]
enabled = true
endpoint = "http://x"
writable = ["SP_*", 3]
color = "red"
[mqtt]
enabled = true
broker = "tcp://b:1883"
group_id = "a/b"
deadband = { float32 = 0.5, word = -1, qword = 1 }
publish_period = 250
''', PROGRAM)
    st, problems = read_station(tmp_path)
    text = "\n".join(problems)
    for key in ("opcua.endpoint", "opcua.writable", "opcua.color", "mqtt.broker", "mqtt.group_id",
                "mqtt.deadband.word", "mqtt.deadband.qword"):
        assert f"station.toml: {key}: " in text, key
    assert st is not None and st.mqtt.deadband == (("float32", 0.5),) and st.mqtt.publish_period == 250


def test_symbols_are_published_where_there_is_no_tags_file() -> None:
    tags = {t.name: t for t in symbol_tags({"START": 0o2000, "LEVEL": 0o4010})}
    assert tags["START"].type is TagType.BIT
    assert tags["LEVEL"].type is TagType.WORD


def test_writes_only_to_writable_tags_and_never_past_a_full_queue() -> None:
    sink = ListSink()
    engine = Engine(parse("JMP 0\n"), sink=sink)
    sp = Tag("SP", 0o4000, TagType.WORD, scaling=Scaling(0, 1000, 0, 100))
    writer = Writer(engine, [sp, Tag("PV", 0o4002)], Writable(["S*"]), sink, lambda: 0.0)
    writer.write("SP", 50.0, "opcua:alice@10.0.0.5:5000")
    engine.scan()
    assert engine.mem.get_word(0o4000) == 500
    written = [r for r in sink.records if r.kind == "operator"]
    assert written[-1].source == "opcua:alice@10.0.0.5:5000" and "SP" in written[-1].text
    with pytest.raises(WriteRefused, match="not writable"):
        writer.write("PV", 1.0, "mqtt:x")
    assert "refused" in sink.records[-1].text and sink.records[-1].source == "mqtt:x"
    for _ in range(MAX_PENDING_WRITES):
        engine.post(lambda _m: None)
    with pytest.raises(WriteRefused, match="queue full"):
        writer.write("SP", 1.0, "opcua:bob")


def test_sparkplug_values_round_trip() -> None:
    p = Payload()
    m = p.metrics.add(name="T", datatype=INT16)
    set_value(m, INT16, -5)
    d = p.metrics.add(name="D", datatype=DOUBLE)
    set_value(d, DOUBLE, float(np.float64(2.5)))
    back = Payload.FromString(p.SerializeToString())
    assert get_value(back.metrics[0]) == -5 and get_value(back.metrics[1]) == 2.5


def test_certificate_made_once_and_kept(tmp_path: Path) -> None:
    cert, key = asyncio.run(station_certificate(tmp_path, "urn:netplc:station:S", "plant-pc", "S"))
    first = cert.read_bytes()
    asyncio.run(station_certificate(tmp_path, "urn:netplc:station:S", "plant-pc", "S"))
    assert cert.read_bytes() == first and key.exists()


def test_an_engine_that_pushes_back_refuses_the_write() -> None:
    class Budgeted(Engine):  # the per-scan write budget, spent
        def write_word(self, addr: int, value: int, *, user: str = "operator",
                       label: str | None = None) -> None:
            raise OverflowError("write budget of this scan spent")

    sink = ListSink()
    engine = Budgeted(parse("JMP 0\n"), sink=sink)
    writer = Writer(engine, [Tag("SP", 0o4000)], Writable(["SP"]), sink, lambda: 0.0)
    with pytest.raises(WriteRefused, match="write queue full"):
        writer.write("SP", 1.0, "opcua:bob")
    assert "refused" in sink.records[-1].text
