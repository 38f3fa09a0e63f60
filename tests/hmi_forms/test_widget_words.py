"""The form widgets speak the console's language: in a Russian console a setpoint, a journal element
and a gauge say nothing in English (their models say English sentences, hmi_forms/elements/sentence.py,
which the widgets translate); the form's own texts stay as the engineer wrote them."""

from __future__ import annotations

import re

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QComboBox, QLabel, QPushButton, QSpinBox

from hmi_forms.elements.analog import DISABLED, NOT_A_NUMBER, OUT_OF_RANGE, SET_TO
from hmi_forms.widgets.analog_output import SENTENCES
from hmi_forms.widgets.form_view import FormView
from tests.hmi_forms.helpers import engine_target
from tests.hmi_forms.test_widgets import differs, engine, image, one

ENGLISH = re.compile(r"\b(?!NetPlc\b)[A-Za-z]{3,}\b")  # a word of three latin letters or more


def shown(view: FormView) -> list[str]:
    """Every text the view's child widgets show (labels, buttons, choices, a spin box's words)."""
    texts = [w.text() for kind in (QLabel, QPushButton) for w in view.findChildren(kind)]
    texts += [c.itemText(i) for c in view.findChildren(QComboBox) for i in range(c.count())]
    texts += [t for s in view.findChildren(QSpinBox) for t in (s.specialValueText(), s.prefix())]
    return [t for t in texts if t]


def test_the_setpoint_says_its_words_in_russian(qtbot, tmp_path, russian) -> None:
    eng, _sink = engine()
    form = one(tmp_path, "AnalogOutput", w=280, h=110, OutAddr="04030", AppMin=0, AppMax=4095, PhyMin=-50,
               PhyMax=150, Units="°C")
    view = FormView(form, engine_target(eng))
    qtbot.addWidget(view)
    widget = view.pairs[0][1]
    assert widget.button.text() == "Задать"
    for entry, said in (("abc", "«abc» — не число"), ("200", "200 вне диапазона -50.0 … 150.0 °C"),
                        ("50", "Задано 50.0 °C")):
        widget.edit.setText(entry)
        widget.submit()
        assert widget.message.text() == said
    assert ENGLISH.findall(" ".join(shown(view))) == []


def test_the_model_says_english_and_the_widget_lists_every_sentence_for_the_translations() -> None:
    assert set(SENTENCES) == {DISABLED, NOT_A_NUMBER, OUT_OF_RANGE, SET_TO}


def test_the_journal_element_says_its_filters_and_status_in_russian(qtbot, tmp_path, russian) -> None:
    form = one(tmp_path, "MessageJournal", w=700, h=240, RefreshTicks=1)
    view = FormView(form, engine_target(engine()[0]), archive_path=tmp_path / "journal.sqlite")
    qtbot.addWidget(view)
    widget = view.pairs[0][1]
    qtbot.waitUntil(lambda: widget.status.text() == "архива ещё нет", timeout=10_000)
    texts = shown(view)
    assert {"Сегодня", "как настроено", "все типы", "все группы"} <= set(texts)
    assert widget.date.displayFormat() == "dd.MM.yyyy"
    heads = [widget.table.headerData(i, Qt.Orientation.Horizontal) for i in range(widget.table.columnCount())]
    assert heads == ["Время", "Вид", "Группа", "Тип", "Источник", "Текст", "Значение"]
    assert ENGLISH.findall(" ".join(texts + heads)) == []
    widget.close_archive()


def test_a_shared_picture_is_drawn_again_in_the_next_language(qtbot, tmp_path, qapp) -> None:
    """A generator's picture ("0: period 5, phase 0") is shared by every widget that looks the same;
    one drawn in English is not shown in a console switched to Russian (the screenshots do that)."""
    from app.gui import i18n

    form = one(tmp_path, "SyncGenerator", w=220, h=80, OutAddr="02001", InAddr="02000", Period0=5)
    pictures = []
    for language in ("en", "ru"):
        i18n.install(qapp, language)
        view = FormView(form, engine_target(engine()[0]))
        qtbot.addWidget(view)
        view.show()
        pictures.append(image(view, qtbot))
    i18n.uninstall(qapp)
    assert differs(*pictures) > 20
