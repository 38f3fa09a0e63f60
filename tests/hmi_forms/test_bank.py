"""The form's bank of plain gauges (hmi_forms/elements/bank.py): words read as one array, and a
gauge settled from them ends up exactly where its own `update` would have put it."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from app.scada.tag import Scaling
from hmi_forms.elements.analog import AnalogBase
from hmi_forms.elements.bank import BitBank, WordBank
from hmi_forms.elements.discrete import DiscreteBase
from hmi_forms.form import load_form
from hmi_forms.widgets.form_view import FormView
from netplc.address import data_address
from netplc.memory import Memory
from tests.hmi_forms.helpers import shown_form, snap

RANGE = {"AppMin": 0, "AppMax": 1000, "PhyMin": -50, "PhyMax": 150}


def test_a_bank_reports_the_words_that_changed_since_they_were_last_taken() -> None:
    bank = WordBank([0o4010, 0o4012, 0o14000])
    assert bank.aligned
    mem = Memory()
    mem.set_word(0o4012, 515)
    assert bank.changed(mem.snapshot(0, 0, 0)) == ([0, 1, 2], [0, 515, 0])  # all new at first
    assert bank.changed(mem.snapshot(1, 0, 0)) == ([], [])
    mem.set_word(0o14000, 0xFFFF)
    assert bank.changed(mem.snapshot(2, 0, 0)) == ([2], [0xFFFF])
    bank.forget(0)
    assert bank.changed(mem.snapshot(3, 0, 0)) == ([0], [0])


def test_words_at_odd_addresses_are_read_byte_by_byte() -> None:
    addresses = [0o4011, 0o4020, 0o17775]
    bank = WordBank(addresses)
    assert not bank.aligned
    mem = Memory()
    for i, a in enumerate(addresses):
        mem.set_word(a, 0x1234 + i)
    words = [mem.snapshot(0, 0, 0).get_word(a) for a in addresses]
    assert bank.changed(mem.snapshot(0, 0, 0)) == ([0, 1, 2], words)


def test_a_word_whose_high_byte_is_past_data_memory_is_refused() -> None:
    with pytest.raises(ValueError, match="past the end"):
        WordBank([data_address(16 * 1024 - 1)])


def test_a_bit_bank_reads_io_bits_and_bits_of_data_bytes() -> None:
    bank = BitBank([0o2001, 0o40013, 0o2002, 0o41000])
    mem = Memory()
    mem.set_hmi_bit(0o2002, 1)
    mem.set_hmi_bit(0o40013, 1)
    assert bank.changed(mem.snapshot(0, 0, 0)) == ([0, 1, 2, 3], [0, 1, 1, 0])
    mem.set_hmi_bit(0o40013, 0)
    mem.set_hmi_bit(0o41000, 1)
    mem.set_hmi_bit(0o2001, 1)
    assert bank.changed(mem.snapshot(1, 0, 0)) == ([0, 1, 3], [1, 0, 1])
    one = BitBank([0o2002])  # a single I/O bit
    assert one.changed(mem.snapshot(2, 0, 0)) == ([0], [1])


def banked(view: FormView) -> list:
    return [model for banked in view._banks for model in banked.models]


def gauge(name: str, x: int, addr: str, **props) -> dict:
    return {"type": "AnalogBase", "Name": name, "x": x, "y": 0, "w": 64, "h": 64, "InAddr": addr,
            **RANGE, "Precision": 1, "Appearance": "dial", **props}


def view_of(qtbot, tmp_path: Path, elements: list[dict]) -> FormView:
    return shown_form(qtbot, tmp_path, elements, (700, 100))


def test_only_gauges_whose_word_is_all_they_show_are_banked(qtbot, tmp_path) -> None:
    view = view_of(qtbot, tmp_path, [
        gauge("plain", 0, "04010", PhyLow=0, PhyHigh=100),
        gauge("digital", 70, "04012", Appearance="digital"),
        gauge("max", 140, "04014", KeepMaxValue=True),
        gauge("hysteresis", 210, "04016", PhyHigh=100, Hysteresis=2),
        gauge("gated", 280, "04020", SyncType="02001"),
        gauge("trend", 350, "04022", Appearance="graph"),
        gauge("io", 420, "0100"),
    ])
    assert [m.Name for m in banked(view)] == ["plain", "digital"]


def test_a_banked_gauge_takes_each_word_as_its_own_update_would(qtbot, tmp_path) -> None:
    """Across zones and precisions, with words that repeat and words that skip: the same value,
    text and zone as a copy of the model refreshed on its own, and the same pixels as a painter."""
    props = [{}, {"PhyLow": 10, "PhyHigh": 90}, {"PhyHigh": 0, "Precision": 0}, {"Precision": 3}]
    view = view_of(qtbot, tmp_path, [gauge(f"G{i}", 70 * i, f"0{0o4010 + 2 * i:o}", **p)
                                     for i, p in enumerate(props)])
    alone = load_form(view.form.path)
    rng = random.Random(16)
    for tick in range(60):
        words = {0o4010 + 2 * i: rng.choice([0, 1, 49, 50, 500, 999, 1000, rng.randrange(1001)])
                 for i in range(len(props))}
        s = snap(words=words, scan=tick)
        view.refresh(s)
        for model, own in zip(banked(view), alone.elements, strict=True):
            assert isinstance(own, AnalogBase)
            own.update(s)
            assert (model.hw, model.phy, model.text, model.zone) == (own.hw, own.phy, own.text, own.zone)
            assert model.shown is own.shown  # one path: what `shows` made of the word, for both
            assert not model.stale
    composed = view.grab().toImage()
    for _, w in view.pairs:
        w.face.forget()  # drawn with a painter, as before any composition
    view.update()
    assert view.grab().toImage() == composed


def test_many_words_settled_at_once_show_what_shows_makes_of_each() -> None:
    """The bank settles a form's plain gauges in one numpy pass (`Settler`): word for word the
    very `Shown` of `shows` (value, text, zone, place), over conversions of every shape."""
    conversions = [(0, 65535, 0, 10000), (0, 1000, -50, 150), (4000, 20000, 0.0, 1.6), (0, 4095, 100, -100),
                   (-32768, 32767, -1.5, 1.5), (0, 999, 0, 0.1)]
    limits = [(None, None), (10.0, 90.0), (None, 0.0), (-0.5, None)]
    rng = random.Random(28)
    models = []
    for k in range(48):
        app_min, app_max, phy_min, phy_max = conversions[k % len(conversions)]
        low, high = limits[k // len(conversions) % len(limits)]
        model = AnalogBase(Name=f"G{k}", InAddr=0o4010 + 2 * k, Precision=k % 4, PhyLow=low, PhyHigh=high)
        model.scaling = Scaling(app_min, app_max, phy_min, phy_max)
        model.remembered = {}  # each its own: nothing remembered from another
        models.append(model)
    settle = AnalogBase.settler(models)
    for _ in range(40):
        positions = sorted(rng.sample(range(len(models)), 30))
        words = [rng.choice([0, 1, 4000, 32767, 65535, rng.randrange(65536)]) for _ in positions]
        for model in models:
            model.remembered.clear()
        for i, word, shown in zip(positions, words, settle(positions, words), strict=True):
            assert models[i].shown is shown and not models[i].stale
            alone = models[i].shows(word)
            assert (shown.hw, shown.phy, shown.text, shown.zone, shown.fraction) == tuple(alone), (i, word)


def test_what_a_gauge_shows_is_its_models_alone(qtbot, tmp_path) -> None:
    """The view reads what the model shows and cannot write it: the parts are read-only and the
    whole is frozen."""
    view = view_of(qtbot, tmp_path, [gauge("G", 0, "04010", PhyHigh=100)])
    view.refresh(snap(words={0o4010: 900}))
    [model] = banked(view)
    assert (model.text, model.zone) == ("130.0", "high")
    with pytest.raises(AttributeError):
        model.text = "0.0"  # type: ignore[misc]
    with pytest.raises(AttributeError):
        model.shown.zone = "normal"  # type: ignore[misc]


def test_a_banked_gauge_that_fails_is_reported_and_the_form_keeps_running(qtbot, tmp_path,
                                                                        monkeypatch) -> None:
    view = view_of(qtbot, tmp_path, [gauge("bad", 0, "04010"), gauge("good", 70, "04012")])
    bad, good = banked(view)

    def broken(hw: int) -> None:
        raise RuntimeError("no conversion")

    monkeypatch.setattr(bad, "settle", broken)
    [words] = [b for b in view._banks if bad in b.models]
    monkeypatch.setattr(words, "settle", lambda *_: broken(0))  # the batch fails: settled one by one
    view.refresh(snap(words={0o4010: 10, 0o4012: 20}))
    assert view.errors == [f'{view.form.path}: element "bad": update failed: RuntimeError(\'no conversion\')']
    assert bad.stale and good.text == "-46.0" and not good.stale
    monkeypatch.undo()
    view.refresh(snap(words={0o4010: 10, 0o4012: 20}, scan=1))  # tried again with the same word
    assert bad.text == "-48.0" and not bad.stale


def test_lamps_whose_bit_is_all_they_show_are_banked_and_follow_it(qtbot, tmp_path) -> None:
    label = {"type": "DiscreteColorLabel", "y": 0, "w": 64, "h": 30, "TextFalse": "OFF", "TextTrue": "ON",
             "BackColorTrue": "#2e7d32"}
    view = view_of(qtbot, tmp_path, [
        {**label, "Name": "io", "x": 0, "InAddr": "02001"},
        {**label, "Name": "data", "x": 70, "InAddr": "040013", "type": "DiscreteColorLabel"},
        {**label, "Name": "enable", "x": 140, "InAddr": "02002", "type": "DiscreteControlledEnable",
         "EnableAddr": "02003"},
        {**label, "Name": "gated", "x": 210, "InAddr": "02004", "SyncType": "02005"},
    ])
    assert [m.Name for m in banked(view)] == ["io", "data"]
    alone = load_form(view.form.path).elements[:2]
    for tick, (a, b) in enumerate([(0, 0), (1, 0), (1, 1), (0, 1), (0, 0)]):
        s = snap(bits={0o2001: a, 0o40013: b}, scan=tick)
        view.refresh(s)
        for model, own in zip(banked(view), alone, strict=True):
            assert isinstance(own, DiscreteBase)
            own.update(s)
            assert (model.value, model.text) == (own.value, own.text)
    composed = view.grab().toImage()
    for _, w in view.pairs:
        w.face.forget()
    view.update()
    assert view.grab().toImage() == composed
