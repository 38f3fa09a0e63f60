"""Each kind of bad form input gets a message naming the file, element, property and problem."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from hmi_forms.form import FormError, load_form, load_forms
from tests.hmi_forms.helpers import write_form

GOOD = {"type": "DiscreteBase", "Name": "Пуск", "x": 10, "y": 10, "w": 100, "h": 40, "InAddr": "040042"}


def problems(tmp_path: Path, elements: list[dict[str, Any]], **extra: Any) -> list[str]:
    path = write_form(tmp_path, elements, **extra)
    with pytest.raises(FormError) as e:
        load_form(path, {"PUMP": 0o2120, "START_WORD": 0o4004})
    return [p.removeprefix(f"{path}: ") for p in e.value.problems]


def test_bad_json_names_line_and_column(tmp_path) -> None:
    path = tmp_path / "bad.hmi"
    path.write_text('{"form": {"width": 10,\n  "height": }\n}', encoding="utf-8")
    with pytest.raises(FormError) as e:
        load_form(path)
    assert e.value.problems == [f"{path}:2:13: bad JSON: Expecting value"]


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        ({"type": "DiscretBase"}, 'type: unknown element type \'DiscretBase\'; did you mean "DiscreteBase"?'),
        ({"InAdr": "02000"}, 'InAdr: unknown property; did you mean "InAddr"?'),
        ({"InAddr": "04008"}, 'InAddr: "04008" is not an octal address or a symbol'),
        ({"InAddr": "010000"}, 'InAddr: 010000 is neither an I/O bit nor a data bit (byte*8+bit)'),
        ({"InAddr": 2000}, 'InAddr: addresses are octal text such as "02000" or a symbol, got 2000'),
        ({"InAddr": "NOPE"}, 'InAddr: unknown symbol "NOPE"'),
        ({"InAddr": "START_WORD.9"}, 'InAddr: bit number after "START_WORD." must be 0-7, got "9"'),
        ({"Enabled": "yes"}, 'Enabled: expected true or false, got "yes"'),
        ({"BackColor": "#12345"}, 'BackColor: "#12345" is not a colour'),
        ({"TextAlign": "Middle"}, 'TextAlign: "Middle" is not one of TopLeft'),
        ({"w": 0}, 'w: 0 is out of range 1..10000'),
        ({"x": 790}, 'w: the element (790,10 100x40) extends past the form (800x600)'),
        ({"Font": {"Size": 2}}, 'Font: font size 2 is out of range 4..200'),
        ({"ImageTrue": 3}, 'ImageTrue: image index 3 is out of range: the form has 0 images'),
        ({"Address": "02000"}, 'Address: given twice (as InAddr and Address)'),
    ],
)
def test_bad_property_values(tmp_path, change: dict[str, Any], expected: str) -> None:
    found = problems(tmp_path, [{**GOOD, **change}])
    assert len(found) == 1 and found[0].startswith('element "Пуск": ' + expected), found


@pytest.mark.parametrize(("kinds", "expected"), [
    (None, "expected a list of record kinds from message, alarm, operator, system, data"),
    (["alarm", "log"], '"log" is not one of message, alarm, operator, system, data'),
])
def test_a_journal_names_bad_record_kinds(tmp_path, kinds: Any, expected: str) -> None:
    """Found by tests/test_loader_fuzz.py: the loader ended in a KeyError (a phrase of no words)."""
    journal = {"type": "MessageJournal", "Name": "j", "x": 10, "y": 10, "w": 100, "h": 40, "Kinds": kinds}
    found = problems(tmp_path, [journal])
    assert len(found) == 1 and found[0].startswith(f'element "j": Kinds: {expected}'), found


def test_missing_required_properties_and_duplicate_names(tmp_path) -> None:
    found = problems(tmp_path, [
        {"type": "DiscreteBase", "Name": "A", "x": 0, "y": 0, "w": 10, "h": 10},
        {**GOOD, "Name": "A"},
        {"type": "StaticText", "x": 0, "y": 0, "w": 10, "h": 10, "Text": "t"},
        {"Name": "B"},
    ])
    assert found == [
        'element "A": InAddr: missing required property',
        'element "A": Name: duplicate element name',
        "element #3: Name: missing required property",
        'element "B": type: missing (types: SyncGenerator, SyncTimer, DiscreteBase, DiscreteColorLabel, '
        "DiscreteControlledEnable, DiscreteAnimation, AnalogBase, AnalogOutput, StaticPicture, StaticText, "
        "Graph, MessageJournal, DateTime)",
    ]


def test_every_problem_of_a_file_is_reported_at_once(tmp_path) -> None:
    found = problems(tmp_path, [{**GOOD, "Enabled": 1}, {**GOOD, "Name": "X", "InAddr": "9"}])
    assert len(found) == 2


def test_devices_and_conversions(tmp_path) -> None:
    analog = {"type": "AnalogBase", "Name": "L", "x": 0, "y": 0, "w": 100, "h": 100, "InAddr": "04010"}
    devices = [{"Name": "Level", "AppMin": 0, "AppMax": 0, "PhyMin": 0, "PhyMax": 100},
               {"Name": "T", "AppMin": 0, "AppMax": 10, "PhyMin": 0},
               {"Name": "U", "AppMin": 0, "AppMax": 10, "PhyMin": 0, "PhyMax": 1, "Gain": 2}]
    found = problems(tmp_path, [{**analog, "Device": "Levl"}, {**analog, "Name": "M"},
                                {**analog, "Name": "N", "AppMin": 0, "AppMax": 10, "PhyMin": 5, "PhyMax": 5},
                                {**analog, "Name": "O", "Device": "U", "PhyMin": 0},
                                {**analog, "Name": "P", "InAddr": "03777"}], devices=devices)
    assert found == [
        'device "Level": AppMax: equals AppMin (0): the conversion is undefined',
        'device "T": PhyMax: missing required property',
        'device "U": Gain: unknown property',
        'element "L": Device: unknown device "Levl" (U)',
        'element "M": Device: missing: name a tag as the address (its conversion is taken), or give a '
        'Device or AppMin, AppMax, PhyMin and PhyMax',
        'element "N": PhyMax: equals PhyMin (5): the conversion is undefined',
        'element "O": PhyMin: give either Device or AppMin/AppMax/PhyMin/PhyMax, not both',
        'element "P": InAddr: 03777: 2-byte operand runs past bit 03777',
    ]


def test_element_cross_checks(tmp_path) -> None:
    found = problems(tmp_path, [
        {"type": "SyncGenerator", "Name": "G", "x": 0, "y": 0, "w": 10, "h": 10, "OutAddr": "02001",
         "Period0": 5, "Phase0": 5},
        {"type": "AnalogBase", "Name": "A", "x": 0, "y": 0, "w": 10, "h": 10, "InAddr": "04010", "AppMin": 0,
         "AppMax": 10, "PhyMin": 0, "PhyMax": 1, "PhyLow": 0.8, "PhyHigh": 0.2, "Appearance": "gauge"},
        {"type": "StaticPicture", "Name": "P", "x": 0, "y": 0, "w": 10, "h": 10, "Image": "missing.png"},
    ])
    assert found == [
        'element "G": Phase0: phase 5 must be less than the period 5',
        'element "A": Appearance: "gauge" is not one of digital, hbar, dial, semidial, graph, tank',
        f'element "P": Image: image file "missing.png" not found in {tmp_path}',
    ]


def test_sections_and_form_settings(tmp_path) -> None:
    path = tmp_path / "f.hmi"
    path.write_text(json.dumps({"form": {"width": 100, "colour": 1}, "element": [], "elements": []}))
    with pytest.raises(FormError) as e:
        load_form(path)
    assert [p.removeprefix(f"{path}: ") for p in e.value.problems] == [
        "file: element: unknown section (form, devices, images, elements)",
        'form: colour: unknown property; did you mean "BackColor"?',
        "form: height: missing required property",
    ]


def test_symbols_name_bits_and_words(tmp_path) -> None:
    path = write_form(tmp_path, [{**GOOD, "InAddr": "START_WORD.2", "OutAddr": "PUMP"}])
    el = load_form(path, {"PUMP": 0o2120, "START_WORD": 0o4004}).elements[0]
    assert el.InAddr.hmi == 0o40042 and el.OutAddr.hmi == 0o2120


def test_one_broken_form_does_not_stop_the_others(tmp_path) -> None:
    write_form(tmp_path, [GOOD], name="a.hmi")
    write_form(tmp_path, [{**GOOD, "Enabled": 1}], name="b.hmi")
    (tmp_path / "c.hmi").write_text("{", encoding="utf-8")
    forms, found = load_forms(tmp_path)
    assert [f.path.name for f in forms] == ["a.hmi"]
    assert len(found) == 2 and "b.hmi" in found[0] and "c.hmi:1:2: bad JSON" in found[1]
