"""The tank appearance: the liquid follows the value, in the zone's colour."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtGui import QColor

from hmi_forms.elements.target import NullTarget
from hmi_forms.form import load_form
from hmi_forms.widgets.form_view import FormView
from hmi_forms.widgets.tank import LIQUID
from tests.hmi_forms.helpers import snap, write_form

LEVEL = 0o4010


def liquid_rows(view: FormView) -> int:
    """Pixel rows of the tank's middle column in the liquid's colour."""
    image = view.grab().toImage()
    return sum(1 for y in range(image.height()) if _close(QColor(image.pixel(50, y)), LIQUID))


def _close(a: QColor, b: QColor) -> bool:
    return abs(a.red() - b.red()) + abs(a.green() - b.green()) + abs(a.blue() - b.blue()) < 12


def test_the_liquid_follows_the_level(qtbot, tmp_path: Path) -> None:
    path = write_form(tmp_path, [{"type": "AnalogBase", "Name": "Ёмкость", "x": 0, "y": 0, "w": 100, "h": 140,
                                  "InAddr": "04010", "AppMin": 0, "AppMax": 4095, "PhyMin": 0, "PhyMax": 100,
                                  "Units": "%", "Appearance": "tank"}])
    form = load_form(path)
    view = FormView(form, NullTarget())
    qtbot.addWidget(view)
    rows = []
    for i, raw in enumerate((410, 2048, 3600)):
        view.refresh(snap(words={LEVEL: raw}, scan=i + 1))
        rows.append(liquid_rows(view))
    assert 0 < rows[0] < rows[1] < rows[2]
    assert 4 < rows[1] / rows[0] < 6  # 10 % and 50 % of the same vessel
