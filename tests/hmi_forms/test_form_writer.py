"""The canonical .hmi writer: fixed key order, an element per block, values as written, no churn."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from app.station.config import DEMO_STATION
from hmi_forms.form import FormError, load_form
from hmi_forms.form_doc import Reader, new_doc, problems, read_doc
from hmi_forms.form_writer import dump_form, element_keys, save_form
from netplc.program import load_symbols

DEMO = DEMO_STATION
FORMS = sorted((DEMO / "forms").glob("*.hmi"))
SYMBOLS = load_symbols(DEMO / "symbols.csv")


@pytest.mark.parametrize("path", FORMS, ids=lambda p: p.name)
def test_demo_form_round_trip_is_byte_identical(path: Path, tmp_path: Path) -> None:
    out = tmp_path / path.name
    save_form(read_doc(path).data, out)
    assert out.read_bytes() == path.read_bytes()


def test_every_demo_form_is_covered() -> None:
    assert [p.name for p in FORMS] == ["01_trigger.hmi", "02_analog.hmi", "03_sync.hmi"]


def test_key_order_is_fixed_whatever_the_input_order() -> None:
    doc = {"elements": [{"h": 20, "TextFalse": "off", "InAddr": "02000", "w": 10, "Name": "a",
                         "BorderStyle": "FixedSingle", "type": "DiscreteBase", "y": 2, "x": 1,
                         "Font": {"Bold": True, "Size": 12, "Family": "DejaVu Sans"}}],
           "form": {"height": 100, "title": "t", "width": 200}}
    text = dump_form(doc)
    assert text == (
        '{\n'
        ' "form": {\n  "title": "t",\n  "width": 200,\n  "height": 100\n },\n'
        ' "elements": [\n'
        '  {\n'
        '   "type": "DiscreteBase",\n'
        '   "Name": "a",\n'
        '   "x": 1, "y": 2, "w": 10, "h": 20,\n'
        '   "InAddr": "02000",\n'
        '   "TextFalse": "off",\n'
        '   "BorderStyle": "FixedSingle",\n'
        '   "Font": {"Family": "DejaVu Sans", "Size": 12, "Bold": true}\n'
        '  }\n'
        ' ]\n'
        '}\n')
    assert json.loads(text) == doc
    assert dump_form(json.loads(text)) == text


def test_values_keep_their_spelling_and_unknown_keys_are_kept_last() -> None:
    doc = {"form": {"title": "t", "width": 100, "height": 100},
           "elements": [{"type": "AnalogBase", "Name": "a", "x": 0, "y": 0, "w": 10, "h": 10,
                         "Colour": "red", "InAddr": "LEVEL", "AppMin": 0, "AppMax": 4095.0,
                         "PhyMin": 0.5, "PhyMax": 100}],
           "extra": [1]}
    back = json.loads(dump_form(doc))
    el = back["elements"][0]
    assert list(el)[-1] == "Colour"
    assert el["AppMax"] == 4095.0 and isinstance(el["AppMax"], float) and isinstance(el["AppMin"], int)
    assert el["InAddr"] == "LEVEL"
    assert list(back) == ["form", "elements", "extra"]


def test_an_alias_is_written_where_its_property_goes() -> None:
    keys = element_keys("Graph")
    assert keys[:8] == ("type", "Name", "x", "y", "w", "h", "Address", "InAddr")
    analog = element_keys("AnalogBase")
    assert analog.index("Arreragance") == analog.index("Appearance") + 1


def test_save_and_reload_gives_the_same_models(tmp_path: Path) -> None:
    for path in FORMS:
        out = tmp_path / "forms" / path.name
        out.parent.mkdir(exist_ok=True)
        (tmp_path / "forms" / "images").mkdir(exist_ok=True)
        for img in (path.parent / "images").glob("*.png"):
            (tmp_path / "forms" / "images" / img.name).write_bytes(img.read_bytes())
        save_form(read_doc(path).data, out)
        a, b = load_form(path, SYMBOLS), load_form(out, SYMBOLS)
        assert [(type(e), e.Name, e.x, e.y, e.w, e.h) for e in a.elements] == \
               [(type(e), e.Name, e.x, e.y, e.w, e.h) for e in b.elements]
        assert (a.title, a.width, a.height, a.devices) == (b.title, b.width, b.height, b.devices)


def test_save_is_atomic_and_leaves_no_temporary_file(tmp_path: Path) -> None:
    path = tmp_path / "f.hmi"
    save_form(new_doc(path).data, path)
    assert [p.name for p in tmp_path.iterdir()] == ["f.hmi"]
    assert read_doc(path).data == new_doc(path).data


def test_problems_of_an_unsaved_document_are_those_of_check(tmp_path: Path) -> None:
    doc = read_doc(FORMS[0])
    assert problems(doc, SYMBOLS) == []
    doc.elements[1]["Address"] = "NO_SUCH"
    found = problems(doc, SYMBOLS)
    assert len(found) == 1 and 'element "ТА: счётный вход": Address: unknown symbol "NO_SUCH"' in found[0]
    path = tmp_path / FORMS[0].name
    save_form(doc.data, path)
    with pytest.raises(Exception) as e:
        load_form(path, SYMBOLS)
    assert [t.replace(str(path), "") for t in e.value.problems] == [  # type: ignore[attr-defined]
        t.replace(str(FORMS[0]), "") for t in found]


def test_reader_refuses_an_edit_that_adds_a_problem_and_draws_a_broken_element() -> None:
    doc = read_doc(FORMS[1])
    reader = Reader(doc, SYMBOLS)
    raw = doc.elements[0]
    assert reader.refusal(raw, dict(raw, InAddr="04010")) is None
    assert reader.refusal(raw, dict(raw, InAddr="010000")) == "InAddr: 010000 is not a valid address"
    assert reader.refusal(raw, dict(raw, PhyLow=95)) == "PhyHigh: 90 must be above PhyLow 95"
    model, found = reader.drawable({"type": "DiscreteBase", "Name": "new", "x": 0, "y": 0, "w": 9, "h": 9})
    assert model is not None and found[0].endswith('element "new": InAddr: missing required property')


def test_the_command_line_re_saves_hand_written_forms(tmp_path: Path,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    from hmi_forms.form_doc import main

    hand = tmp_path / "hand.hmi"
    hand.write_text('{"elements": [{"Name": "a", "type": "StaticText", "Text": "t",'
                    ' "x": 0, "y": 0, "w": 5, "h": 5}], "form": {"width": 10, "height": 10, "title": "f"}}',
                    encoding="utf-8")
    bad = tmp_path / "bad.hmi"
    bad.write_text("{", encoding="utf-8")
    assert main([str(hand), str(bad)]) == 1
    assert "bad.hmi:1:2: bad JSON" in capsys.readouterr().err
    assert hand.read_text(encoding="utf-8") == dump_form(json.loads(hand.read_text(encoding="utf-8")))
    assert hand.read_text(encoding="utf-8").startswith('{\n "form": {\n  "title": "f",')


@pytest.mark.parametrize(("text", "says"), [
    ('{"form": {"width": 1' + "0" * 5000 + "}}", "4300 digits"),
    ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
    ('{"form": ', "bad JSON"),
])
def test_a_form_the_designer_cannot_open_is_a_named_error(tmp_path, text: str, says: str) -> None:
    """The designer reads a form as the loader does (hmi_forms.form.parse_form): never a traceback."""
    path = tmp_path / "broken.hmi"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(FormError) as e:
        read_doc(path)
    assert e.value.problems[0].startswith(str(path)) and says in e.value.problems[0]
