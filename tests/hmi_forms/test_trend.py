"""Form trends really rendered: the line where its samples are, gaps at bad quality, the axes'
labels where they must be and whole, on a bit trend, an analog trend and the demo's forms."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from PySide6.QtCore import QPoint, QPointF, Qt
from PySide6.QtGui import QColor, QImage, QWheelEvent
from PySide6.QtWidgets import QApplication

from app.station.config import DEMO_STATION
from hmi_forms.elements.analog import AnalogBase
from hmi_forms.elements.target import NullTarget
from hmi_forms.form import load_form, load_forms
from hmi_forms.widgets import theme
from hmi_forms.widgets.form_view import FormView
from hmi_forms.widgets.trend import TrendWidget
from hmi_forms.widgets.trend_axes import value_ticks
from netplc.engine import FakeClock
from netplc.program import load_symbols
from tests.hmi_forms.helpers import write_form

T0 = 1_800_000_000.0
PERIOD = 0.1


@pytest.fixture
def view(qtbot, tmp_path: Path) -> FormView:
    doc = write_form(tmp_path, [
        {"type": "Graph", "Name": "bit", "x": 0, "y": 0, "w": 400, "h": 160, "Address": "040005",
         "Elements": 100, "LineWidth": 2},
        {"type": "AnalogBase", "Name": "temp", "x": 0, "y": 170, "w": 400, "h": 200, "InAddr": "04010",
         "Device": "T", "Units": "°C", "Appearance": "graph", "Elements": 100, "PhyLow": 0, "PhyHigh": 120}],
        devices=[{"Name": "T", "AppMin": 0, "AppMax": 4095, "PhyMin": -50, "PhyMax": 150}])
    form = load_form(doc)
    form.width, form.height = 400, 380
    view = FormView(form, NullTarget(), clock=FakeClock())
    qtbot.addWidget(view)
    view.resize(400, 380)
    view.show()
    return view


def fill(trend: TrendWidget, value: object, n: int = 100) -> float:
    """n samples a scan apart, `value(k)` each; the time of the last."""
    for k in range(n):
        trend.trend.add(value(k), T0 + k * PERIOD)
    return T0 + (n - 1) * PERIOD


def picture(view: FormView, trend: TrendWidget, wall: float) -> QImage:
    view.redraw_trends(wall)
    return trend.plot.grab().toImage()


def near(image: QImage, x: float, y: float, color: QColor, reach: int = 1) -> bool:
    """`color` at (x, y), give or take `reach` px."""
    return any(QColor(image.pixel(round(x) + dx, round(y) + dy)) == color
               for dx in range(-reach, reach + 1) for dy in range(-reach, reach + 1)
               if 0 <= round(x) + dx < image.width() and 0 <= round(y) + dy < image.height())


def x_of(trend: TrendWidget, t: float) -> float:
    r, (t0, t1) = trend.axes.plot, trend.window()
    return r.left() + (t - t0) * r.width() / (t1 - t0)


def inked(image: QImage, left: float, top: float, width: float, height: float) -> int:
    """Pixels of text (darker than the grid) in the rectangle."""
    return sum(QColor(image.pixel(x, y)).lightness() < 160
               for x in range(max(0, int(left)), min(image.width(), math.ceil(left + width)))
               for y in range(max(0, int(top)), min(image.height(), math.ceil(top + height))))


def test_a_bit_trend_draws_its_samples_in_steps_with_gaps_at_bad_quality(view: FormView) -> None:
    bit = view.trends[0]
    wall = fill(bit, lambda k: math.nan if 60 <= k < 70 else float(k < 40))
    image = picture(view, bit, wall)
    assert bit.window() == pytest.approx((wall - 10.0, wall))  # 100 samples of 0.1 s: 10 s live
    one, zero = bit.axes.y_of(1.0, bit.scale), bit.axes.y_of(0.0, bit.scale)
    pen = QColor(theme.ACCENT)
    assert near(image, x_of(bit, T0 + 2.0), one, pen) and not near(image, x_of(bit, T0 + 2.0), zero, pen, 0)
    assert near(image, x_of(bit, T0 + 5.0), zero, pen) and not near(image, x_of(bit, T0 + 5.0), one, pen, 0)
    x = x_of(bit, T0 + 4.0)  # the step from 1 to 0, drawn 2 px wide (LineWidth 2)
    assert near(image, x, (one + zero) / 2, pen, 0) and near(image, x + 1, (one + zero) / 2, pen, 0)
    for t in (6.3, 6.6):  # bad quality: no line at all
        assert not any(near(image, x_of(bit, T0 + t), y, pen, 0) for y in range(image.height()))
    assert near(image, x_of(bit, T0 + 8.0), zero, pen)  # and back after it
    labels = dict(bit.axes.labels)
    assert labels["1"].center().y() == pytest.approx(one, abs=1) and "0" in labels
    assert labels["0 s"].right() <= image.width() and labels["-2 s"].center().x() == pytest.approx(
        x_of(bit, wall - 2.0), abs=1)
    for text, where in bit.axes.labels:  # drawn where they are said to be
        assert inked(image, where.left(), where.top(), where.width(), where.height()) > 3, text


def test_an_analog_trend_shows_its_scale_unit_and_limits(view: FormView) -> None:
    temp = view.trends[1]
    wall = fill(temp, lambda k: -50 + 2.0 * k)  # -50 .. 148 °C
    image = picture(view, temp, wall)
    axes, pen = temp.axes, QColor(theme.ACCENT)
    for k in (10, 50, 90):
        assert near(image, x_of(temp, T0 + k * PERIOD), axes.y_of(-50 + 2.0 * k, temp.scale), pen)
    texts = [text for text, _ in axes.labels]
    assert "°C" in texts and "150" in texts and "-50" in texts and "0 s" in texts
    y = round(axes.y_of(120, temp.scale))  # PhyHigh, dashed in the alarm colour
    dashes = (QColor(image.pixel(x, y)) == theme.ALARM for x in range(int(axes.plot.left()), image.width()))
    assert sum(dashes) > 50
    header = temp.grab().toImage()  # the value with its unit in the header
    assert inked(header, header.width() - 120, 0, 100, temp.header) > 20


def test_paused_the_axis_shows_clock_times_and_a_drag_pans_every_trend(qtbot, view: FormView) -> None:
    bit, temp = view.trends
    wall = fill(bit, lambda k: float(k % 20 < 10))
    fill(temp, lambda k: 20.0)
    view.redraw_trends(wall)
    live = [text for text, _ in bit.axes.labels]
    start = QPoint(200, 40)
    qtbot.mousePress(bit.plot, Qt.MouseButton.LeftButton, pos=start)
    qtbot.mouseMove(bit.plot, start + QPoint(60, 0))
    qtbot.mouseRelease(bit.plot, Qt.MouseButton.LeftButton, pos=start + QPoint(60, 0))
    assert not view.live and temp.window() == bit.window() and bit.window()[1] < wall - 1
    bit.plot.grab()
    paused = [text for text, _ in bit.axes.labels]
    assert paused != live and all(":" in text for text in paused if text not in ("0", "1"))


def test_value_ticks_are_round_and_apart() -> None:
    assert value_ticks(0, 100, 200, 20) == [(v, str(v)) for v in range(0, 101, 10)]
    assert value_ticks(-50, 150, 100, 20) == [(-50.0, "-50"), (0.0, "0"), (50.0, "50"), (100.0, "100"),
                                              (150.0, "150")]
    assert [text for _, text in value_ticks(0, 1, 100, 20)] == ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]
    assert value_ticks(0, 0, 100, 20) == []


def test_no_axis_label_of_the_demo_forms_is_cut(qtbot) -> None:
    """Every label of every trend of the demo's forms, at their size (1:1 at 1366x768), lies
    whole inside its trend, the value labels left of the plot, the time labels under it."""
    forms, _ = load_forms(DEMO_STATION / "forms", load_symbols(DEMO_STATION / "symbols.csv"))
    views = [FormView(form, NullTarget(), clock=FakeClock()) for form in forms]
    for view in views:
        qtbot.addWidget(view)
        view.show()
    trends = [(view, trend) for view in views for trend in view.trends]
    assert len(trends) >= 5 and any(isinstance(t.model, AnalogBase) for _, t in trends)
    for view, trend in trends:
        lo, hi = trend.lo, trend.hi
        wall = fill(trend, lambda k, lo=lo, hi=hi: lo + (hi - lo) * (k % 7) / 7)
        image = picture(view, trend, wall)
        r = trend.axes.plot
        assert len(trend.axes.labels) >= 4
        for text, where in trend.axes.labels:
            assert where.left() >= 0 and where.right() <= image.width(), text
            assert where.top() >= 0 and where.bottom() <= image.height(), text
            assert where.right() <= r.left() or where.top() >= r.bottom(), text  # beside or under the plot
            assert inked(image, where.left(), where.top(), where.width(), where.height()) > 3, text


def test_the_wheel_zooms_about_the_mouse_and_the_mouse_reads_a_sample(qtbot, view: FormView) -> None:
    bit, temp = view.trends
    wall = fill(bit, lambda k: float(k % 20 < 10))
    fill(temp, lambda k: 20.0 + k)
    view.redraw_trends(wall)
    r = temp.axes.plot
    at = QPointF(r.center().x(), r.center().y())
    before, under = temp.window(), temp.plot.time_at(at.x())
    wheel = QWheelEvent(at, temp.plot.mapToGlobal(at), QPoint(), QPoint(0, 120), Qt.MouseButton.NoButton,
                        Qt.KeyboardModifier.NoModifier, Qt.ScrollPhase.NoScrollPhase, False)
    QApplication.sendEvent(temp.plot, wheel)
    t0, t1 = temp.window()
    assert not view.live and bit.window() == (t0, t1)
    assert t1 - t0 == pytest.approx((before[1] - before[0]) * 0.8)  # one notch in
    assert temp.plot.time_at(at.x()) == pytest.approx(under)  # about the time under the mouse
    plain = temp.plot.grab().toImage()
    qtbot.mouseMove(temp.plot, at.toPoint())
    qtbot.waitUntil(lambda: temp.plot.mouse is not None, timeout=5000)
    read = temp.plot.grab().toImage()
    t, _ = temp.value_at(temp.plot.time_at(temp.plot.mouse.x()))
    x = round(r.left() + (t - t0) * r.width() / (t1 - t0))
    bottom = round(r.bottom())
    dots = [QColor(read.pixel(x, y)) == theme.TEXT_DIM for y in range(bottom - 8, bottom)]
    assert any(dots) and not all(dots)  # the dotted line at the sample
    assert inked(read, r.left(), r.top(), r.width(), 16) > inked(plain, r.left(), r.top(), r.width(), 16) + 20
