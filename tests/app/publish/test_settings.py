"""[opcua] and [mqtt] in station.toml, the published points and the write rules, without a network."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from app.authority import Commands, Reason, Source, Who
from app.publish import sparkplug as spb
from app.publish.devices import Layout
from app.publish.points import PointWriter, Writable, symbol_tags
from app.publish.sparkplug import DOUBLE, INT16, Payload, get_value, set_value
from app.scada.quality import Quality, QualityMap
from app.scada.tag import TagType
from app.station.config import load_station, read_station
from netplc.engine import Engine
from netplc.exchange import NodeConfig
from netplc.program import parse
from netplc.records import ListSink
from tests.app.conftest import write_station

PROGRAM = {"p.stl": "JMP 0\n"}


def test_defaults_are_off_loopback_and_read_only(tmp_path: Path) -> None:
    st = load_station(write_station(tmp_path, 'NetPlcProgram = "p.stl"\n', PROGRAM))
    assert not st.opcua.enabled and st.opcua.endpoint == "opc.tcp://127.0.0.1:4840/netplc/"
    assert st.opcua.writable == () and st.mqtt.writable == ()
    assert not st.mqtt.enabled and st.mqtt.edge_node_id == ""
    assert st.mqtt.primary_host == "" and st.mqtt.role == "operator"  # no host awaited; NCMD may write


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
primary_host = "SCADA/1"
role = "boss"
deadband = { float32 = 0.5, word = -1, qword = 1 }
publish_period = 250
''', PROGRAM)
    st, problems = read_station(tmp_path)
    text = "\n".join(problems)
    assert "station.toml: opcua.certificate_names: 'bad name' is not a host name or an IP address" in text
    assert "station.toml: opcua.certificate_names: 7 is not a host name or an IP address" in text
    assert st is not None and st.opcua.certificate_names == ("plant-pc.example.org", "10.1.2.3")
    for key in ("opcua.endpoint", "opcua.writable", "opcua.color", "mqtt.broker", "mqtt.group_id",
                "mqtt.deadband.word", "mqtt.deadband.qword", "mqtt.primary_host", "mqtt.role"):
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


def test_every_quality_is_one_of_the_three_sparkplug_codes_and_an_initial_value_is_null() -> None:
    """Sparkplug 3.0 allows Quality 0 (BAD), 192 (GOOD) and 500 (STALE) only, an Int32."""
    assert set(spb.QUALITY_CODES) == set(Quality)
    assert set(spb.QUALITY_CODES.values()) == {spb.BAD, spb.GOOD, spb.STALE} == {0, 192, 500}
    p = Payload()
    for code in Quality:
        spb.set_reading(p.metrics.add(name=code.word, datatype=DOUBLE), DOUBLE, 12.5, int(code))
    back = {m.name: m for m in Payload.FromString(p.SerializeToString()).metrics}
    assert back["initial"].is_null and back["initial"].WhichOneof("value") is None
    assert back["initial"].properties.values[0].int_value == spb.BAD
    assert back["comm-fail"].double_value == 12.5
    assert back["comm-fail"].properties.values[0].int_value == spb.STALE
    assert back["forced"].properties.values[0].type == spb.INT32


def test_a_state_payload_is_sparkplug_3_json_or_refused_with_why() -> None:
    state = spb.parse_state(b'{"online": true, "timestamp": 1668114759262}')
    assert state == spb.HostState(True, 1668114759262)
    assert spb.parse_state(b'{"timestamp": 5, "online": false}') == spb.HostState(False, 5)
    for data, why in ((b"ONLINE", "not UTF-8 JSON"), (b"\xff", "not UTF-8 JSON"),
                      (b"[1]", "not a JSON object"),
                      (b'{"online": "yes", "timestamp": 1}', "'online' is 'yes'"),
                      (b'{"online": true}', "'timestamp' is None"),
                      (b'{"online": true, "timestamp": -1}', "'timestamp' is -1"),
                      (b'{"online": true, "timestamp": true}', "'timestamp' is True")):
        with pytest.raises(ValueError, match=why):
            spb.parse_state(data)
    assert spb.state_topic("SCADA") == "spBv1.0/STATE/SCADA"


def test_a_point_is_a_device_metric_of_the_one_node_whose_nreads_fill_it() -> None:
    """Points filled by node 1's NREADs are device Pumps's, by node 2's device Node2's; what no NREAD
    or two nodes fill is the edge node's. Aliases stay the point's index + 1, the link metrics after."""
    program = parse("FON C:$2000 N:NODE S:1\nFON C:$2004 N:NREAD S:4000 D:$4000 R:4\n"
                    "FON C:$2010 N:NODE S:2\nFON C:$2014 N:NREAD S:4000 D:$4004 R:2\n"
                    "FON C:$2020 N:NREAD S:4000 D:$4003 R:2\n")
    tags = symbol_tags({"A": 0o4000, "B": 0o4004, "AB": 0o4003, "SP": 0o4100, "BIT": 0o40001})
    nodes = [NodeConfig(2, "tcp://127.0.0.1:1"), NodeConfig(1, "tcp://127.0.0.1:2", name="Pumps")]
    layout = Layout(tags, QualityMap(program, tags), nodes)
    names = [t.name for t in tags]
    assert [d.id for d in layout.devices] == ["Pumps", "Node2"]
    pumps, node2 = layout.devices
    assert [names[i] for i in pumps.points] == ["A", "BIT"] and [names[i] for i in node2.points] == ["B"]
    assert [names[i] for i in layout.node_points] == ["AB", "SP"]
    assert pumps.first_alias == len(tags) + 1 and node2.first_alias == len(tags) + 5
    assert layout.point(pumps, "A", 0) == 0 and layout.point(pumps, "", 1) == 0  # by name or alias
    assert layout.point(None, "A", 0) is None and layout.point(node2, "", 1) is None  # not theirs
    assert layout.point(None, "SP", 0) == names.index("SP") and layout.point(None, "", 99) is None
    assert layout.link_name(node2, "", node2.first_alias + 2) == "Link/LastError"
    assert layout.link_name(node2, "Link/Up", 0) == "Link/Up" and layout.link_name(node2, "A", 0) == ""
