"""Role and Confirm on the elements that write: read from the form, checked, and asked through the
view's guard before anything is written."""

from __future__ import annotations

from pathlib import Path

import pytest

from hmi_forms.form import FormError, load_form
from tests.hmi_forms.helpers import ListTarget, snap, write_form

BUTTON = {"type": "DiscreteBase", "Name": "Пуск", "x": 0, "y": 0, "w": 80, "h": 30, "InAddr": "040042",
          "Enabled": True}
SETPOINT = {"type": "AnalogOutput", "Name": "Уставка", "x": 0, "y": 40, "w": 200, "h": 80, "OutAddr": "04030",
            "AppMin": 0, "AppMax": 4095, "PhyMin": 0, "PhyMax": 100}


def test_role_and_confirm_are_read_and_checked(tmp_path: Path) -> None:
    form = load_form(write_form(tmp_path, [{**BUTTON, "Role": "engineer", "Confirm": True}, SETPOINT]))
    button, setpoint = form.elements
    assert (button.Role, button.Confirm) == ("engineer", True)
    assert (setpoint.Role, setpoint.Confirm) == ("operator", False)  # the defaults
    with pytest.raises(FormError) as e:
        load_form(write_form(tmp_path, [{**BUTTON, "Role": "boss"}], name="bad.hmi"))
    assert 'element "Пуск": Role: "boss" is not one of viewer, operator, engineer, admin' in str(e.value)


def test_the_guard_decides_before_anything_is_written(tmp_path: Path) -> None:
    button, setpoint = load_form(write_form(tmp_path, [BUTTON, SETPOINT])).elements
    target = ListTarget()
    asked: list[str] = []
    answer: list[str | None] = ["needs the engineer role"]

    def guard(element, what: str) -> str | None:
        asked.append(what)
        return answer[0]

    for model in (button, setpoint):
        model.bind(target, "ivan")
        model.guard = guard
    button.update(snap())
    assert button.click() is False
    assert setpoint.submit("50") == (False, "needs the engineer role")
    assert not target.writes and asked == ["Пуск \u2192 1", "Уставка \u2192 50.0"]
    answer[0] = None
    assert button.click() is True and setpoint.submit("50")[0]
    assert target.writes == [("bit", 0o40042, 1, "ivan"), ("word", 0o4030, 2048, "ivan")]


def test_a_confirmation_names_the_tag_not_the_type_and_says_the_state(tmp_path: Path) -> None:
    """The designer's "DiscreteBase" bound to a tag is asked about by the tag's description, the
    new state in the element's words; the target is given the label the journal names."""
    from app.scada.table import TagTable
    from app.scada.tag import Scaling, Tag, TagType

    tags = TagTable([Tag("PUMP", 0o40042, TagType.BIT, description="Насос"),
                     Tag("SP", 0o4030, TagType.WORD, "°C", Scaling(0, 4095, -50, 150), 1, "Уставка")])
    button = {**BUTTON, "Name": "DiscreteBase 2", "InAddr": "PUMP", "TextFalse": "Стоп", "TextTrue": "Пуск"}
    setpoint = {"type": "AnalogOutput", "Name": "AnalogOutput", "x": 0, "y": 40, "w": 200, "h": 80,
                "OutAddr": "SP"}
    plain = {**BUTTON, "Name": "DiscreteBase 3", "InAddr": "040043", "y": 100}
    models = load_form(write_form(tmp_path, [button, setpoint, plain]), tags=tags).elements
    asked: list[str] = []
    for model in models:
        model.bind(ListTarget(), "ivan")
        model.guard = lambda _element, what: asked.append(what) or "no"
        model.update(snap())
    models[0].click()
    models[1].submit("20")
    models[2].click()
    assert asked == ["Насос \u2192 Пуск", "Уставка \u2192 20.0 °C", "040043 \u2192 1"]
    assert [m.label for m in models] == ["Насос", "Уставка", ""]
