"""[opcua] and [mqtt] in station.toml, the published points and the write rules, without a network."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from app.authority import Commands, Reason, Source, Who
from app.publish.points import PointWriter, Writable, symbol_tags
from app.publish.sparkplug import DOUBLE, INT16, Payload, get_value, set_value
from app.scada.tag import TagType
from app.station.config import load_station, read_station
from netplc.engine import Engine
from netplc.program import parse
from netplc.records import ListSink
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
certificate_names = ["plant-pc.example.org", "10.1.2.3", "bad name", 7]
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
    assert "station.toml: opcua.certificate_names: 'bad name' is not a host name or an IP address" in text
    assert "station.toml: opcua.certificate_names: 7 is not a host name or an IP address" in text
    assert st is not None and st.opcua.certificate_names == ("plant-pc.example.org", "10.1.2.3")
    for key in ("opcua.endpoint", "opcua.writable", "opcua.color", "mqtt.broker", "mqtt.group_id",
                "mqtt.deadband.word", "mqtt.deadband.qword"):
        assert f"station.toml: {key}: " in text, key
    assert st is not None and st.mqtt.deadband == (("float32", 0.5),) and st.mqtt.publish_period == 250


def test_symbols_are_published_where_there_is_no_tags_file() -> None:
    tags = {t.name: t for t in symbol_tags({"START": 0o2000, "LEVEL": 0o4010})}
    assert tags["START"].type is TagType.BIT
    assert tags["LEVEL"].type is TagType.WORD


def test_sparkplug_values_round_trip() -> None:
    p = Payload()
    m = p.metrics.add(name="T", datatype=INT16)
    set_value(m, INT16, -5)
    d = p.metrics.add(name="D", datatype=DOUBLE)
    set_value(d, DOUBLE, float(np.float64(2.5)))
    back = Payload.FromString(p.SerializeToString())
    assert get_value(back.metrics[0]) == -5 and get_value(back.metrics[1]) == 2.5


def test_symbols_are_written_through_the_layer_as_bits_and_words() -> None:
    """Where a station has no tags.csv its symbols are the points: a client writes a bit or an
    unsigned word, never outside it, and only what `writable` names."""
    sink = ListSink()
    engine = Engine(parse("JMP 0\n"), sink=sink)
    layer = Commands(engine, sink, role_of={"olga": "operator"}.get)
    tags = {t.name: t for t in symbol_tags({"START": 0o2000, "SP": 0o4010, "PV": 0o4012})}
    writer = PointWriter(layer, Writable(["S*"]), "[mqtt]")
    olga = Who("olga", Source.MQTT, "broker:1883")
    started, word = writer.write(olga, tags["START"], True), writer.write(olga, tags["SP"], 1234)
    engine.scan()
    assert engine.mem.bits[0o2000] == 1 and engine.mem.get_word(0o4010) == 1234
    assert started.result(1).ok and word.result(1).ok
    answers = [writer.write(olga, tags["SP"], 70000), writer.write(olga, tags["SP"], 1.5),
               writer.write(olga, tags["PV"], 1), writer.write(olga, tags["SP"], 1, "a String for a UInt16"),
               writer.write(Who("", Source.OPCUA), tags["SP"], 1, "a String for a UInt16")]
    assert [a.result(0).reason for a in answers] == [
        Reason.OUT_OF_RANGE, Reason.TYPE_MISMATCH, Reason.NOT_WRITABLE, Reason.TYPE_MISMATCH, Reason.DENIED]
