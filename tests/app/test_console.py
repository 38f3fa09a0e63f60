"""The operator console on the demo station: a screen that does not move under the hand, and
fits a 1366x768 screen whatever the forms hold; its users and roles, its language, its trends; a
tag's faceplate; from an alarm to its place on the picture. One console serves the module's tests
that leave it as they found it."""

from __future__ import annotations

import datetime as dt
import gc
import math
import sqlite3
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from PySide6.QtCore import QEvent, QPoint, Qt
from PySide6.QtWidgets import QPlainTextEdit

from app import __version__
from app.gui.faceplate import Faceplate
from app.gui.main_window import MainWindow
from app.gui.navigate import Highlight
from app.gui.zoom import ACTUAL, FIT_WIDTH, FIT_WINDOW
from app.station.config import load_station
from app.station.runtime import Runtime
from hmi_forms.elements import formats
from netplc.address import fmt_octal
from registrar.query import Archive
from tests.app.conftest import copy_demo

LEVEL = 0o4010
START_BIT = 0o40042
BROKEN = ('{"form": {"title": "broken", "width": 100, "height": 100}, "elements": [{"type": "StaticText", '
          '"Name": "' + "a_very_long_element_name_" * 40 + '", "x": "not a number"}]}')


LEVEL_TAG = "LEVEL,LEVEL,word,%,0,4095,0,100,1,Уровень,95,90,,,2,2,1,"  # the demo's: on after 2 s


def open_console(folder: Path) -> MainWindow:
    """The demo's console in English, started: its tests read the journal word for word; its users
    at the tests' cheap scrypt cost (tests/cheap_users.py); a broken form among its forms; LEVEL's
    alarms on 0.2 s after the limit rather than the demo's 2 s (no test of it is about the delay:
    tests/app/scada/ are)."""
    demo_copy = copy_demo(folder, "en")
    (demo_copy / "forms" / "99_broken.hmi").write_text(BROKEN, encoding="utf-8")
    tags = demo_copy / "tags.csv"
    text = tags.read_text(encoding="utf-8")
    assert LEVEL_TAG in text
    tags.write_text(text.replace(LEVEL_TAG, LEVEL_TAG.replace(",2,2,1,", ",2,0.2,1,")), encoding="utf-8")
    runtime = Runtime(load_station(demo_copy))
    runtime.start()
    window = MainWindow(runtime)
    window.resize(1366, 768)
    window.show()
    return window


def reset(window: MainWindow, idle: tuple[float, Callable[[], float]]) -> None:
    """What a test left on the module's console that the next one could mistake for its own: the
    user on duty, the answers given for the operator, the session's clock, the faceplates and
    windows opened, the message said, the form shown."""
    vars(window).pop("ask", None)
    window.session.idle, window.session.clock = idle
    window.log_out()
    window.faceplates.close()
    for opened in window.viewers:
        opened.close()
    window.viewers.clear()
    window.programs.clear()
    window.status.clearMessage()
    window.tabs.setCurrentIndex(0)


def close_shared(qapp, window: MainWindow) -> None:
    """A module's console closed, its station stopped, and the window freed on the GUI thread
    (app/gui/application.py) before the next module starts."""
    window.close()
    window.runtime.stop()
    window.deleteLater()
    qapp.sendPostedEvents(None, QEvent.Type.DeferredDelete.value)
    del window
    gc.collect()


@pytest.fixture(scope="module")
def shared_console(qapp, tmp_path_factory: pytest.TempPathFactory) -> Iterator[MainWindow]:
    """One console for the module's tests that leave the station running, its users as they were
    and put back what they change (`reset` after each): a console and its station cost more to
    build than most of these tests take."""
    window = open_console(tmp_path_factory.mktemp("console") / "station")
    try:
        yield window
    finally:
        close_shared(qapp, window)


@pytest.fixture(scope="module")
def russian_console(qapp, tmp_path_factory: pytest.TempPathFactory) -> Iterator[MainWindow]:
    """The demo's console in the demo's Russian (its station's language, installed as `main.py`
    does before the window is made), for the module's tests of the language; each test installs
    the translation again for itself (the `russian` fixture)."""
    from app.gui import i18n

    demo_copy = copy_demo(tmp_path_factory.mktemp("russian") / "station")
    assert i18n.install(qapp, load_station(demo_copy).Language) == "ru"
    runtime = Runtime(load_station(demo_copy))
    runtime.start()
    window = MainWindow(runtime)
    try:
        yield window
    finally:
        close_shared(qapp, window)


@pytest.fixture
def console(shared_console: MainWindow) -> Iterator[MainWindow]:
    """The module's console (`shared_console`), the default viewer on duty, and reset after the test."""
    idle = shared_console.session.idle, shared_console.session.clock
    yield shared_console
    reset(shared_console, idle)


@pytest.fixture
def own_console(qtbot, tmp_path: Path) -> Iterator[MainWindow]:
    """A console of the test's own, for a test that stops its station, quits it or changes its users."""
    window = open_console(tmp_path / "station")
    qtbot.addWidget(window)
    try:
        yield window
    finally:
        window.close()
        window.runtime.stop()


def test_a_broken_form_does_not_widen_the_window(qtbot, console: MainWindow) -> None:
    qtbot.waitUntil(lambda: console.health.isVisible(), timeout=5000)
    assert "a_very_long_element_name_" in console.health.label.text()
    assert console.minimumSizeHint().width() <= 1366
    assert console.width() == 1366
    assert console.health.label.shown().endswith("…")  # elided, the whole of it one click away
    dialog = console.health.show_details()
    details = dialog.findChild(QPlainTextEdit)
    assert "a_very_long_element_name_" in details.toPlainText()
    dialog.close()


def test_the_forms_stay_put_when_an_alarm_comes(qtbot, console: MainWindow) -> None:
    runtime = console.runtime
    qtbot.waitUntil(lambda: runtime.status().nodes_up == 1, timeout=10_000)
    top = console.tabs.mapTo(console, console.tabs.rect().topLeft())
    # a loaded machine may have made a tag stale for a moment at start (an alarm of its own)
    runtime.simulators[0].engine.write_word(LEVEL, 3700)
    qtbot.waitUntil(lambda: any(row.tag == "LEVEL" for row in console.alarms.alarms), timeout=5000)
    qtbot.wait(50)
    assert console.alarms.isVisible()
    assert console.tabs.mapTo(console, console.tabs.rect().topLeft()) == top
    console.alarms.acknowledge_all()
    qtbot.wait(50)
    assert console.tabs.mapTo(console, console.tabs.rect().topLeft()) == top


def scans_later(qtbot, runtime: Runtime, scans: int = 2) -> None:
    """Back once the engine has run `scans` more scans: a command queued before is applied at the
    start of the next scan, so whatever was sent by then shows in the snapshot now."""
    engine = runtime.engine
    assert engine is not None
    start = engine.scan_counter
    qtbot.waitUntil(lambda: engine.scan_counter >= start + scans, timeout=5000)


def element(window: MainWindow, name: str):
    for view in window.views:
        for model, widget in view.pairs:
            if model.Name == name:
                return model, widget
    raise AssertionError(f"no element {name!r}")


def operator_rows(runtime: Runtime) -> list[tuple[str, str]]:
    con = sqlite3.connect(f"file:{runtime.station.Archive}?mode=ro", uri=True)
    try:
        return con.execute(f'SELECT source, text FROM "{dt.date.today():%d_%m_%Y}" WHERE kind = ? '
                           "ORDER BY id", ("operator",)).fetchall()
    finally:
        con.close()


def committed(qtbot, runtime: Runtime) -> None:
    """Back once every record journaled so far is in the archive's file (the writer commits it at
    once for the barrier), for a test that reads the journal while its station runs on."""
    done = threading.Event()
    runtime.after_commit(done.set)
    qtbot.waitUntil(done.is_set, timeout=10_000)


class Answers:
    """The operator's answers to the confirmations, and the questions asked."""

    def __init__(self, answer: bool) -> None:
        self.answer = answer
        self.asked: list[str] = []

    def __call__(self, title: str, text: str) -> bool:
        self.asked.append(f"{title}: {text}")
        return self.answer


def test_the_demo_opens_as_its_viewer_who_may_not_act(qtbot, console: MainWindow) -> None:
    engine = console.runtime.engine
    assert console.user == "viewer" and console.header.user.text() == "viewer\nviewer"
    model, button = element(console, "Пуск")
    qtbot.waitUntil(lambda: model.value is not None, timeout=5000)
    assert "Пуск: needs the operator role; viewer is viewer" in button.toolTip()  # it keeps its look
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    assert console.status.currentMessage() == "Refused: Пуск: needs the operator role; viewer is viewer"
    assert console.note.isVisible() and console.note.text() == console.status.currentMessage()  # whole
    assert console.note.width() <= console.width()
    setpoint, _ = element(console, "Уставка температуры")
    ok, why = setpoint.submit("50")
    assert not ok and why == "Уставка температуры: needs the operator role; viewer is viewer"
    assert not console.alarms.ack.isEnabled() and "needs the operator role" in console.alarms.ack.toolTip()
    scans_later(qtbot, console.runtime)
    assert engine.snapshot.get_hmi_bit(START_BIT) == 0


def test_run_stop_and_quit_need_the_engineer_and_ask(qtbot, own_console: MainWindow) -> None:
    console = own_console
    runtime = console.runtime
    console.ask = no = Answers(False)
    console.login("operator", "operator")
    assert not console.act_stop.isEnabled()
    assert "Stop NetPlc: needs the engineer role" in console.act_stop.toolTip()
    console.stop_program()  # asked all the same (a script, a shortcut): the layer refuses it
    assert "Stop NetPlc: needs the engineer role; operator is operator" in console.status.currentMessage()
    console.request_quit()
    assert "Quit: needs the engineer role" in console.status.currentMessage() and console.isVisible()
    assert not no.asked  # refused before anything is asked
    console.login("engineer", "engineer")
    assert console.act_stop.isEnabled() and console.act_quit.isEnabled()
    assert console.stop_program() is None and console.request_quit() is None  # answered no
    assert console.isVisible()
    assert [q.split(":")[0] for q in no.asked] == ["Stop NetPlc", "Quit"]
    scans_later(qtbot, runtime)
    assert runtime.status().state == "running"  # both answered no
    console.ask = Answers(True)
    console.stop_program()
    qtbot.waitUntil(lambda: runtime.status().state != "running", timeout=3000)
    console.refresh_status()
    assert console.act_run.isEnabled() and not console.act_stop.isEnabled()
    console.run_program()
    qtbot.waitUntil(lambda: runtime.status().state == "running", timeout=3000)
    console.request_quit()
    qtbot.waitUntil(lambda: not console.isVisible(), timeout=3000)  # closed once the layer answered
    runtime.stop()
    rows = operator_rows(runtime)
    assert rows[-5:] == [("operator", "logged out: user switched"), ("engineer", "logged in as engineer"),
                         ("engineer", "NetPlc stopped"), ("engineer", "NetPlc started"),
                         ("engineer", "station quit")]


def test_ctrl_q_and_f5_no_longer_act_at_once(console: MainWindow) -> None:
    assert console.act_run.shortcut().isEmpty() and console.act_stop.shortcut().isEmpty()
    assert console.act_quit.shortcut().toString() == "Ctrl+Q"
    console.ask = Answers(True)
    assert not console.act_quit.isEnabled()  # the viewer may not quit the station
    assert console.act_quit.toolTip() == "Quit: needs the engineer role; viewer is viewer"
    console.act_quit.trigger()
    assert console.isVisible()


def test_an_element_asks_when_the_form_says_confirm_and_checks_its_role(qtbot, console: MainWindow) -> None:
    engine = console.runtime.engine
    model, button = element(console, "Пуск")
    qtbot.waitUntil(lambda: model.value == 0, timeout=5000)
    console.login("operator", "operator")
    confirm, role = model.Confirm, model.Role
    try:
        model.Confirm = True
        console.ask = no = Answers(False)
        assert model.click() is False
        assert no.asked == ["Confirm: Пуск \u2192 Пуск (1)?"]  # the state in the element's words
        scans_later(qtbot, console.runtime)
        assert engine.snapshot.get_hmi_bit(START_BIT) == 0
        console.ask = Answers(True)
        qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
        qtbot.waitUntil(lambda: engine.snapshot.get_hmi_bit(START_BIT) == 1, timeout=3000)
        model.Role = "engineer"
        qtbot.waitUntil(lambda: model.value == 1, timeout=3000)
        assert model.click() is False
        assert "Пуск: needs the engineer role; operator is operator" in console.status.currentMessage()
    finally:
        model.Confirm, model.Role = confirm, role
    committed(qtbot, console.runtime)
    writes = [t for s, t in operator_rows(console.runtime) if s == "operator" and "Пуск" in t]
    assert writes == ["write Пуск (040042): 0 -> 1",
                      "refused write Пуск: needs the engineer role; operator is operator"]


def test_an_idle_user_is_logged_out_and_it_is_journaled(qtbot, console: MainWindow) -> None:
    now = [0.0]
    console.session.clock = lambda: now[0]
    console.session.idle = 900
    console.login("operator", "operator")
    assert console.user == "operator"
    now[0] += 901
    console.refresh_status()
    assert console.user == "viewer" and "Log in" in console.header.login.text()
    committed(qtbot, console.runtime)
    assert operator_rows(console.runtime)[-1] == ("operator", "logged out: idle")


def test_every_demo_form_fits_a_1366x768_window(qtbot, console: MainWindow) -> None:
    assert console.minimumSizeHint().width() <= 1366
    assert console.zooms and len(console.zooms) == len(console.views)
    for i, area in enumerate(console.zooms):
        console.tabs.setCurrentIndex(i)
        area.set_mode(FIT_WINDOW)
        qtbot.wait(20)
        assert area.viewport().width() > 1000
        assert not area.cut_off(), (area.form_view.form.path.name, area.shown_rect(), area.viewport().rect())
        image = console.grab().toImage()
        assert image.width() == 1366 and image.height() == 768
    area = console.zooms[0]
    console.tabs.setCurrentIndex(0)
    area.set_mode(ACTUAL)
    assert area.factor == 1.0 and area.cut_off()  # 760 px of form above the journal: it needs the zoom
    area.set_mode(FIT_WINDOW)  # as it was


def test_the_zoom_is_remembered_per_form(qtbot, console: MainWindow) -> None:
    first, second = console.zooms[0], console.zooms[1]
    console.tabs.setCurrentIndex(1)
    second.set_mode(FIT_WIDTH)
    first.zoom_by(-2)
    factor = first.factor
    again = MainWindow(console.runtime)
    qtbot.addWidget(again)
    try:
        assert again.zooms[1].mode == FIT_WIDTH
        assert again.zooms[0].mode == "" and abs(again.zooms[0].factor - factor) < 0.001
        assert again.zooms[2].mode == FIT_WINDOW  # the default
    finally:
        again.close()
        first.set_mode(FIT_WINDOW)  # as they were
        second.set_mode(FIT_WINDOW)


def test_the_trends_of_a_form_share_one_time_axis(qtbot, console: MainWindow) -> None:
    from hmi_forms.widgets.trend_axes import ago_label, clock_label

    view = console.views[0]
    first, second = view.trends[:2]
    qtbot.waitUntil(lambda: first.trend.count > 15 and second.trend.count > 15, timeout=10_000)
    view.flush()
    assert first.scale.live and second.scale.live  # live: seconds before now
    t0, t1 = first.window()
    assert second.window() == (t0, t1)
    assert abs(t1 - view._last.wall) < 0.01 and t1 - t0 > 10  # ending now
    assert first.shown == first.trend.count and second.shown == second.trend.count  # redrawn together
    (t, after), v = first.trend.times()[-3:-1], first.trend.values()[-3]
    # the cursor reads the nearest sample: a quarter of the way to the next (a loaded machine's
    # refresh may come late and the next early, 20 ms after it)
    assert first.value_at(t + (after - t) / 4) == (t, v)
    assert ago_label(-10, 5) == "-10 s" and ago_label(-120, 60) == "-2 min"
    assert clock_label(t, 1) == formats.clock(t)

    area = second.axes.plot  # drag the second trend's curves 100 px to the right: back in time
    start = QPoint(round(area.center().x()) - 50, round(area.center().y()))
    qtbot.mousePress(second.plot, Qt.MouseButton.LeftButton, pos=start)
    qtbot.mouseMove(second.plot, start + QPoint(100, 0))
    qtbot.mouseRelease(second.plot, Qt.MouseButton.LeftButton, pos=start + QPoint(100, 0))
    assert not view.live and first.pause_button.text() == "\u25b6" and not first.scale.live  # clock times
    moved = second.window()
    assert first.window() == moved and moved[1] < t1 - 1  # linked
    count = first.trend.count
    qtbot.waitUntil(lambda: first.trend.count > count + 12, timeout=10_000)
    assert first.window() == moved  # paused: it stays where it was put
    first.pause_button.click()
    assert view.live and first.scale.live
    assert abs(first.window()[1] - view._last.wall) < 0.01


def level_samples(archive: Path) -> int:
    """The level's samples in today's archive (NSTORE of LEVEL, once a second)."""
    if not archive.exists():
        return 0
    reader = Archive(archive)
    try:
        return len(reader.series(dt.date.today(), source=fmt_octal(LEVEL))[0])
    finally:
        reader.close()


def test_a_trend_starts_with_the_archives_history(qtbot, console: MainWindow) -> None:
    """A window opened on a station whose archive holds the level's samples (the module's, run a
    while: NSTORE once a second) starts its trend with them."""
    runtime = console.runtime
    qtbot.waitUntil(lambda: level_samples(runtime.station.Archive) > 1, timeout=15_000)  # committed
    window = MainWindow(runtime)
    qtbot.addWidget(window)
    try:
        level = next(t for v in window.views for t in v.trends if t.model.Name == "Уровень, тренд")
        qtbot.waitUntil(lambda: len(level.hist_times) > 1, timeout=10_000)
        assert level.hist_times[-1] < runtime.wallclock()
        values = [v for v in level.hist_values if not math.isnan(v)]  # NaN: a gap (a stale sample)
        assert values and all(0 <= v <= 100 for v in values)  # raw NSTORE words, scaled to %
    finally:
        window.close()


def test_about_names_the_version(console: MainWindow) -> None:
    assert f"NetPlc Station {__version__}" in console.about_text()


def test_the_console_speaks_russian_and_the_forms_keep_their_texts(
        qtbot, russian, russian_console: MainWindow) -> None:
    from app.gui import i18n

    assert i18n.compiled("ru") is not None  # the .ts in the repository compiles with PySide6's lrelease
    window = russian_console
    menus = [a.text() for a in window.menuBar().actions()]
    assert menus == ["&Станция", "&Вид", "&Справка"]
    assert window.act_run.text() == "&Запустить NetPlc…" and window.act_quit.text() == "В&ыход…"
    heads = [window.journal.model.headerData(i, Qt.Orientation.Horizontal) for i in range(3)]
    assert heads == ["Время", "Вид", "Группа"]
    assert window.alarms.ack.text() == "Квитировать"
    assert window.header.quiet.text() == "Нет неквитированных аварий"
    window.refresh_status()
    assert window.status.state.text() == "NetPlc: работает"
    assert window.journal.windowTitle() == "Журнал — сегодня"
    titles = [v.form.title for v in window.views]
    assert [window.tabs.tabText(i) for i in range(3)] == titles  # as the engineer wrote them
    assert "Пуск" in [m.Name for v in window.views for m in v.form.elements]
    import datetime as dt

    assert window.header.clock.text().startswith(f"{dt.date.today():%d.%m.%Y}")


def test_refusals_roles_and_alarms_speak_russian_too(qtbot, russian, russian_console: MainWindow) -> None:
    """What the Qt-free models say in English (users.py refusals, roles, alarm priorities and
    states, qualities) the console shows in its language; the journal is in the station's (the
    demo's Russian)."""
    import dataclasses

    from app.gui.alarms import AlarmBanner
    from app.gui.status import station_problems
    from app.scada.alarms import AlarmRow, State
    from hmi_forms.widgets.base import quality_tip

    window = russian_console
    runtime = window.runtime
    window.refresh_status()  # the rights said again in the translation installed for this test
    assert window.header.user.text() == "viewer\nнаблюдатель"
    model, button = element(window, "Пуск")
    qtbot.waitUntil(lambda: model.value is not None, timeout=5000)
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    assert window.status.currentMessage() == "Отказано: Пуск: нужна роль «оператор»; viewer — наблюдатель"
    assert "нужна роль «оператор»" in window.alarms.ack.toolTip()
    assert "Выход: нужна роль «инженер»" in window.act_quit.toolTip()
    committed(qtbot, runtime)  # the journal speaks the station's language
    assert ("viewer", "отказ: запись Пуск: нужна роль «оператор»; viewer — наблюдатель") in [
        (s, t.split(" (")[0]) for s, t in operator_rows(runtime)]
    summary = window.summary
    heads = [summary.model.headerData(i, Qt.Orientation.Horizontal, Qt.ItemDataRole.DisplayRole)
             for i in range(6)]
    assert heads == ["Приоритет", "Время", "Авария", "Состояние", "Значение при изменении", "Текст"]
    assert summary.counts[1].text().startswith("P1 критическая: ")
    assert summary.shelve.text() == "Отложить…" and window.summary_dock.windowTitle().startswith("Аварии")
    shown = (State.UNACK, State.ACKED, State.RTNUN, State.SHELVED, State.SUPPRESSED, State.OUT_OF_SERVICE)
    rows = [AlarmRow(f"A{s}", 2, s, 1.0, 1.0, None, "текст") for s in shown]
    summary.model.set_rows(rows)
    display = Qt.ItemDataRole.DisplayRole
    states = [summary.model.data(summary.model.index(i, 3), display) for i in range(6)]
    assert states == ["активна, не квитирована", "активна, квитирована", "вернулась, не квитирована",
                      "отложена", "подавлена", "выведена из работы"]
    assert summary.model.data(summary.model.index(0, 0), Qt.ItemDataRole.DisplayRole) == "2 высокая"
    banner = AlarmBanner()
    qtbot.addWidget(banner)
    banner.show_alarms(rows[:1])
    assert "P2 ВЫСОКАЯ" in banner.text.text() and "активна, не квитирована" in banner.text.text()
    assert quality_tip("comm-fail").startswith("? нет связи")
    stopped = dataclasses.replace(runtime.status(), state="stopped")
    assert "NetPlc: остановлен" in station_problems(stopped)


def test_the_language_comes_from_station_toml(demo_copy: Path) -> None:
    assert load_station(demo_copy).Language == "ru"  # the demo's forms are Russian: so is its console
    toml = demo_copy / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8").replace('Language = "ru"', 'Language = "en"'),
                    encoding="utf-8")
    assert load_station(demo_copy).Language == "en"


def test_only_an_admin_manages_users_and_it_is_journaled(qtbot, console: MainWindow) -> None:
    from app.authority.users import Users

    users = console.session.users  # the station's users.json, which the dialog changes
    before = dict(users.users)
    try:
        for name in ("operator", "engineer"):
            console.login(name, name)
            assert console.manage_users() is None
            assert f"Users: needs the admin role; {name} is {name}" in console.status.currentMessage()
        console.login("admin", "admin")
        dialog = console.manage_users()
        assert dialog is not None and dialog.table.rowCount() == 4
        assert dialog.add_user("ivan", "operator", "pw") and dialog.table.rowCount() == 5
        assert not dialog.add_user("ivan", "viewer", "x")
        assert dialog.message.text() == ("Add user ivan: user 'ivan' exists already (passwd changes the "
                                         "password)")
        assert dialog.set_password("ivan", "new") and dialog.remove_user("viewer")
        console.log_out()  # the dialog left open: its changes are the commands of whoever is on duty, now
        assert not dialog.remove_user("ivan")  # the default viewer, just removed
        assert dialog.message.text() == "Remove user ivan: viewer is no longer a user (admin needed)"
        dialog.close()
        folder = console.runtime.station.folder
        assert Users(folder).verify("ivan", "new").role == "operator" and Users(folder).get("viewer") is None
        committed(qtbot, console.runtime)
        rows = [(s, t) for s, t in operator_rows(console.runtime) if s == "admin"]
        assert rows[-5:] == [("admin", "user ivan added as operator"),
                             ("admin", "refused users ivan: user 'ivan' exists already (passwd changes the "
                                       "password)"),
                             ("admin", "password of ivan changed"), ("admin", "user viewer removed"),
                             ("admin", "logged out")]
    finally:  # the module's users as they were
        users.users.clear()
        users.users.update(before)
        users.save()


def test_the_header_says_while_forces_are_active_and_the_element_shows_f(qtbot, console: MainWindow) -> None:
    from app.authority import Source, Who
    from hmi_forms.widgets import theme

    runtime = console.runtime
    model, widget = element(console, "Уставка температуры")
    ticket = runtime.commands.force_tag(Who("engineer", Source.CONSOLE), "TEMP_SP", 20.0)
    assert ticket.result(5).ok
    qtbot.waitUntil(lambda: "1 forces active" in console.health.problems, timeout=5000)
    assert console.health.problems[0] == "1 forces active" and console.health.isVisible()
    qtbot.waitUntil(lambda: model.quality == "forced", timeout=5000)
    assert widget.stale_mark.word == "forced"
    image = widget.grab().toImage()
    forced = theme.FORCED.rgb()
    assert any(image.pixel(x, 1) == forced for x in range(image.width()))  # the orange frame, no hatch
    assert runtime.commands.unforce_all(Who("engineer", Source.CONSOLE)).result(5).ok
    qtbot.waitUntil(lambda: "1 forces active" not in console.health.problems, timeout=5000)


# --- a tag's faceplate, opened from an element of the demo's forms: the live value with its
# quality and unit, the tag's alarms, a trend, and the actions the user's role allows, each a
# command of the station's layer

SETPOINT = 0o4030


def open_plate(qtbot, window: MainWindow, name: str) -> Faceplate:
    _, widget = element(window, name)
    qtbot.mouseDClick(widget, Qt.MouseButton.LeftButton)
    plate = window.faceplates.open[window.faceplates.bound[widget].name]
    assert isinstance(plate, Faceplate) and plate.isVisible()
    return plate


def test_a_double_click_opens_the_tags_faceplate_live(qtbot, console: MainWindow) -> None:
    plate = open_plate(qtbot, console, "Температура")
    assert plate.tag.name == "TEMP" and "Температура" in plate.windowTitle() + plate.findChild(
        type(plate.value), "faceplateTitle").text()
    qtbot.waitUntil(lambda: plate.value.text().endswith("°C") and plate.quality.text() == "good",
                    timeout=10_000)
    assert set(plate.alarm_rows) == {"TEMP.HH", "TEMP.H", "TEMP.BAD"}  # limits and quality
    qtbot.waitUntil(lambda: plate.points() >= 2, timeout=10_000)  # the trend runs
    assert plate.set.isHidden()  # a measurement: no form sets it, nor does its faceplate
    assert not plate.force.isEnabled() and "needs the engineer role" in plate.force.toolTip()
    plate.grab()
    again = open_plate(qtbot, console, "Температура, °C")  # one faceplate per tag
    assert again is plate


def test_the_faceplate_sets_forces_and_unforces_as_the_user_on_duty(qtbot, console: MainWindow) -> None:
    engine = console.runtime.engine
    console.login("operator", "operator")
    plate = open_plate(qtbot, console, "Уставка температуры")
    assert plate.tag.name == "TEMP_SP" and not plate.set.isHidden()
    qtbot.waitUntil(lambda: plate.set.isEnabled(), timeout=5000)
    assert not plate.force.isEnabled()
    plate.entry.setText("100")
    plate.set_value()
    qtbot.waitUntil(lambda: engine.snapshot.get_word(SETPOINT) == round(150 / 200 * 4095), timeout=5000)
    plate.entry.setText("900")  # outside PhyMin..PhyMax: the layer refuses, in words
    plate.set_value()
    qtbot.waitUntil(lambda: "outside" in plate.message.text(), timeout=5000)

    console.login("engineer", "engineer")
    qtbot.waitUntil(lambda: plate.force.isEnabled(), timeout=5000)
    console.ask = asked = Answers(True)
    plate.force_entry.setText("1000")
    assert plate.force_value() is None and not asked.asked  # refused before asking
    assert plate.message.text() == ("TEMP_SP is not forced: 1000.0 °C is outside its range "
                                    "-50.0 °C .. 150.0 °C")
    plate.force_entry.setText("20")
    plate.force_value()
    assert asked.asked[-1].startswith("Force: Force TEMP_SP to 20.0 °C?")
    qtbot.waitUntil(lambda: plate.forced.text() == "F forced by engineer", timeout=5000)
    qtbot.waitUntil(lambda: plate.value.text() == "20.0 °C", timeout=5000)
    plate.unforce_value()
    assert asked.asked[-1] == ("Unforce: Unforce TEMP_SP? The memory keeps 20.0 °C, the forced value, until "
                               "the program, a node or an operator writes it.")
    qtbot.waitUntil(lambda: plate.forced.text() == "", timeout=5000)
    assert plate.value.text() == "20.0 °C"  # the forced value stays


# --- from an alarm to its place on the picture: a double-click on an alarm (summary, banner,
# journal) brings up the form with its tag's element, marked; a form's tab shows the highest
# priority of the unacknowledged alarms on it


def test_a_double_clicked_alarm_shows_its_element_and_the_tab_is_marked(qtbot, console: MainWindow) -> None:
    runtime = console.runtime
    qtbot.waitUntil(lambda: runtime.status().nodes_up == 1, timeout=10_000)
    analog = next(i for i, v in enumerate(console.views) if v.form.path.stem == "02_analog")
    # no precondition on the tab's mark: on a loaded PC the demo's node-fed tags may have gone stale
    # (a quality alarm on the form) before the test begins; the unmarked tab is checked at the end
    runtime.simulators[0].engine.write_word(LEVEL, 3950)  # 96 %: LEVEL.HH and LEVEL.H
    qtbot.waitUntil(lambda: any(a.id == "LEVEL.HH" for a in console.alarms.alarms), timeout=10_000)
    qtbot.waitUntil(lambda: not console.tabs.tabIcon(analog).isNull(), timeout=5000)
    assert console.tabs.tabToolTip(analog).startswith("P")
    console.tabs.setCurrentIndex(0)
    level = [r for r in console.summary.unacknowledged() if r.id.startswith("LEVEL.")]
    console.alarms.show_alarms(level)  # the banner's first alarm a LEVEL one, whatever else came
    qtbot.mouseDClick(console.alarms, Qt.MouseButton.LeftButton)  # the banner: its first alarm
    assert console.tabs.currentIndex() == analog
    mark = console.navigator.highlight
    assert isinstance(mark, Highlight) and mark.isVisible()
    shown = [w for w, tag in console.faceplates.bound.items() if tag.name == "LEVEL"]
    assert any(mark.geometry().contains(w.geometry()) for w in shown)
    console.tabs.setCurrentIndex(0)
    rows = console.summary.model.rows
    row = next(i for i, r in enumerate(rows) if r.id == "LEVEL.H")
    console.summary.table.doubleClicked.emit(console.summary.model.index(row, 0))
    assert console.tabs.currentIndex() == analog
    journal = console.journal

    def level_alarms() -> list[int]:
        rows = journal.model.rows
        return [i for i, r in enumerate(rows) if r.kind == "alarm" and r.source.startswith("LEVEL.")]

    qtbot.waitUntil(lambda: bool(level_alarms()), timeout=10_000)
    console.tabs.setCurrentIndex(0)
    record = level_alarms()[0]
    journal.table.doubleClicked.emit(journal.model.index(record, 0))  # an alarm record of the journal
    assert console.tabs.currentIndex() == analog
    console.navigator.mark_tabs([])  # as when every alarm is acknowledged
    assert console.tabs.tabIcon(analog).isNull() and console.tabs.tabToolTip(analog) == ""
    console.navigator.mark_tabs(level[:1])
    assert not console.tabs.tabIcon(analog).isNull()
