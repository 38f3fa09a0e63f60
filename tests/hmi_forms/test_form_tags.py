"""Form elements may name a tag of tags.csv instead of an address: the element takes the tag's
conversion, unit, decimals and L/H limits unless the form gives them; a wrong tag is named."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.scada.table import load_tags
from hmi_forms.elements.analog import AnalogBase, AnalogOutput
from hmi_forms.elements.discrete import DiscreteBase
from hmi_forms.form import FormError, load_form
from netplc.engine import Engine
from netplc.program import parse
from netplc.records import ListSink
from tests.hmi_forms.helpers import engine_target, snap, write_form

TAGS = """\
name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description,h,l,priority
LEVEL,04010,word,%,0,4095,0,100,2,Уровень,90,10,2
PUMP,040005,bit,,,,,,,Насос,,,
"""
BOX = {"x": 10, "y": 10, "w": 200, "h": 100}


@pytest.fixture
def tags(tmp_path: Path):
    path = tmp_path / "tags.csv"
    path.write_text(TAGS, encoding="utf-8")
    return load_tags(path)


def test_an_element_naming_a_tag_takes_its_scale_unit_and_limits(tmp_path: Path, tags) -> None:
    path = write_form(tmp_path, [
        {"type": "AnalogBase", "Name": "L", **BOX, "InAddr": "LEVEL"},
        {"type": "AnalogBase", "Name": "Own", **BOX, "InAddr": "LEVEL", "Units": "проц.", "Precision": 0,
         "AppMin": 0, "AppMax": 1000, "PhyMin": 0, "PhyMax": 10, "PhyHigh": 95},
        {"type": "AnalogOutput", "Name": "Out", **BOX, "OutAddr": "LEVEL"},
        {"type": "DiscreteBase", "Name": "P", **BOX, "InAddr": "PUMP"},
    ])
    level, own, out, pump = load_form(path, tags=tags).elements
    assert isinstance(level, AnalogBase) and isinstance(own, AnalogBase) and isinstance(out, AnalogOutput)
    assert level.InAddr == 0o4010 and level.tag == "LEVEL"
    assert level.scaling.to_phy(4095) == 100 and level.Units == "%" and level.Precision == 2
    assert (level.PhyLow, level.PhyHigh) == (10, 90)
    assert own.scaling.to_phy(1000) == 10 and own.Units == "проц." and own.Precision == 0
    assert (own.PhyLow, own.PhyHigh) == (10, 95)  # what the form gives wins, the rest from the tag
    assert out.OutAddr == 0o4010 and out.tag == "LEVEL" and out.scaling.to_phy(4095) == 100
    assert isinstance(pump, DiscreteBase) and pump.InAddr is not None and pump.InAddr.hmi == 0o40005


def test_an_unknown_tag_and_a_tag_of_the_wrong_type_are_named(tmp_path: Path, tags) -> None:
    path = write_form(tmp_path, [
        {"type": "AnalogBase", "Name": "A", **BOX, "InAddr": "LEVL"},
        {"type": "AnalogBase", "Name": "B", **BOX, "InAddr": "PUMP"},
        {"type": "DiscreteBase", "Name": "C", **BOX, "InAddr": "LEVEL"},
    ])
    with pytest.raises(FormError) as e:
        load_form(path, tags=tags)
    found = [p.removeprefix(f"{path}: ") for p in e.value.problems]
    assert found == ['element "A": InAddr: unknown tag or symbol "LEVL"',
                     'element "B": InAddr: tag "PUMP" is of type bit; this property takes word',
                     'element "C": InAddr: tag "LEVEL" is of type word; this property takes bit']


def test_an_operator_write_to_a_tag_is_journaled_in_physical_units_with_the_raw_value(tmp_path: Path) -> None:
    path = tmp_path / "tags.csv"
    path.write_text("name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description\n"
                    "TEMP_SP,04030,word,°C,0,4095,-50,150,1,Уставка\nSTART,040042,bit,,,,,,,Пуск\n",
                    encoding="utf-8")
    sink = ListSink()
    engine = Engine(parse("JMP 0\n"), sink=sink)
    engine.mem.set_word(0o4030, 1024)  # 0.0 °C
    target = engine_target(engine, load_tags(path))
    target.write_word(0o4030, 3686, user="ivanov", label="Уставка температуры")
    target.write_bit(0o40042, 1, user="ivanov", label="Пуск")
    target.write_word(0o4100, 7, user="ivanov", label="Other")
    engine.scan()
    texts = [(r.source, r.value, r.text) for r in sink.records if r.kind == "operator"]
    assert texts[0] == ("ivanov", 3686.0, "write Уставка температуры TEMP_SP: 0.0 -> 130.0 °C "
                                          "(raw 1024 -> 3686 at 04030)")
    assert texts[1][2] == "write Пуск START (040042): 0 -> 1"
    assert texts[2][2] == "write Other (04100): 0 -> 7"  # no tag: as before


def test_a_setpoint_without_a_tag_journals_its_own_physical_values(tmp_path: Path) -> None:
    """The designer's "AnalogOutput" with its own conversion: the record names no type and no raw
    word alone, but the physical values and unit of the element's conversion."""
    sink = ListSink()
    engine = Engine(parse("JMP 0\n"), sink=sink)
    engine.mem.set_word(0o4030, 1024)  # 0.0 °C
    own = {"type": "AnalogOutput", "Name": "AnalogOutput", **BOX, "OutAddr": "04030", "AppMin": 0,
           "AppMax": 4095, "PhyMin": -50, "PhyMax": 150, "Units": "°C"}
    form = load_form(write_form(tmp_path, [own]))
    setpoint = form.elements[0]
    setpoint.bind(engine_target(engine), "ivanov")
    setpoint.update(snap(words={0o4030: 1024}))
    assert setpoint.submit("130")[0]
    engine.scan()
    texts = [r.text for r in sink.records if r.kind == "operator"]
    assert texts == ["write 04030: 0.0 -> 130.0 °C (raw 1024 -> 3686 at 04030)"]


def test_a_default_named_element_journals_by_its_tags_description(tmp_path: Path, tags) -> None:
    from tests.hmi_forms.helpers import ListTarget

    lamp = {"type": "DiscreteBase", "Name": "DiscreteBase 2", **BOX, "InAddr": "PUMP", "RegMessages": True,
            "TextFalse": "стоп", "TextTrue": "работа"}
    model = load_form(write_form(tmp_path, [lamp]), tags=tags).elements[0]
    model.effects = effects = ListTarget()
    model.update(snap())
    model.update(snap(bits={0o40005: 1}))
    assert [(r.source, r.text) for r in effects.records] == [("Насос", "работа")]
