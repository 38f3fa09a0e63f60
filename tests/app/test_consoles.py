"""Remote consoles (`main.py console opc.tcp://...`): the demo station running headless with its
OPC UA endpoint on a free loopback port, consoles attached in-process (offscreen) as different
users of it, each a real asyncua client of the real endpoint, their views really rendered. What a
console does is the station's command as its user; what it shows is the station's: its forms, alarms,
journal, trends and a tag's faceplate. One station and one console per user serve the module."""

from __future__ import annotations

import datetime as dt
import gc
import json
import math
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
from PySide6.QtCore import Qt, QTime

from app.authority import Answer
from app.gui.console.source import StationSource
from app.gui.console.window import ConsoleWindow
from app.gui.faceplate import Faceplate
from app.gui.status import StationStatusBar
from app.publish.client import LoginError
from app.publish.console import ConsoleClient
from app.publish.index_range import numeric_range
from app.publish.memory_items import WHOLE, Ranges, ranges_of
from app.scada.alarms import State
from app.scada.quality import Quality
from app.scada.readings import Readings
from app.station.config import load_station
from app.station.runtime import Runtime
from hmi_forms.elements.analog import AnalogBase
from hmi_forms.elements.base import Writer
from hmi_forms.widgets.form_view import FormView
from netplc.address import DATA_SIZE, IO_BITS
from netplc.records import Record
from registrar.store import Store
from tests.app.conftest import REPO, copy_demo
from tests.app.publish.conftest import demo_with, free_port
from tests.app.test_console import Answers, element

WAIT = 30_000  # ms: a loaded CI machine; every wait ends on its event
ANALOG = 1  # the demo's analog form (02_analog.hmi), the second tab


class Station:
    """The demo station serving OPC UA on loopback (users viewer, operator, engineer: their password
    their name), restartable on the same port; the consoles attached to it, one per user."""

    def __init__(self, folder: Path) -> None:
        self.port = free_port()
        self.url = f"opc.tcp://127.0.0.1:{self.port}/netplc/"
        self.folder = folder / "st"
        self.records: list[Record] = []
        self.consoles: dict[str, ConsoleWindow] = {}
        self.runtime = demo_with(self.folder, f'[opcua]\nenabled = true\nendpoint = "{self.url}"\n',
                                 self.records)

    def stop(self) -> None:
        self.runtime.stop()

    def close_consoles(self) -> None:
        """Log the consoles out and close them, on the GUI thread (app/gui/application.py)."""
        for window in self.consoles.values():
            window.close()
            window.deleteLater()
        self.consoles.clear()
        gc.collect()

    def restart(self) -> None:
        self.runtime = Runtime(load_station(self.folder))
        self.runtime.subscribe(self.records.append)
        self.runtime.start()


@contextmanager
def serving(folder: Path) -> Iterator[Station]:
    """The station of `folder` (the demo copied to `folder/st`, unless there already) while in it;
    its consoles closed at the end."""
    st = Station(folder)
    try:
        yield st
    finally:
        st.close_consoles()
        st.stop()


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Station, list[float], list[float]]]:
    """The module's station, its archive holding LEVEL's NSTORE series of the minute before it
    started: raw words 0, 40, 80, ... (0 %, ~1 %, ~2 % ...), one a gap; and in that minute two
    messages, an alarm ("Насос 2 остановлен", type 2) and an info one (type 0), and an operator's
    record; and before them TEMP's NSTORE series of the half hour before it started: a raw 500
    (50.0 °C) a minute. The other tests look at none of them."""
    folder = tmp_path_factory.mktemp("consoles")
    station = copy_demo(folder / "st")
    t = time.time()
    store = Store(station / "archive" / "journal.sqlite")
    store.start()
    hour = [t - 1800 + 60 * k for k in range(25)]
    for ts in hour:
        store.put(Record(ts, "data", grp=1, type=2, source="04012", value=500))
    times = [t - 60 + 0.5 * k for k in range(100)]
    journal = {10: Record(times[10], "message", grp=1, type=2, number=901, text="Насос 2 остановлен"),
               20: Record(times[20], "message", grp=1, type=0, number=902, text="Насос 2 в работе"),
               30: Record(times[30], "operator", source="olga@10.0.0.21", text="write Уставка: 1 -> 2")}
    for k, ts in enumerate(times):  # in time order, as a station writes
        store.put(Record(ts, "data", grp=1, type=1, source="04010", value=None if k == 50 else 40 * k,
                         text="comm-fail" if k == 50 else None))
        if k in journal:
            store.put(journal[k])
    store.close()
    with serving(folder) as st:
        yield st, times, hour


@pytest.fixture(scope="module")
def station(served: tuple[Station, list[float], list[float]]) -> Station:
    return served[0]


@pytest.fixture(scope="module")
def archived(served: tuple[Station, list[float], list[float]]) -> tuple[Station, list[float]]:
    """The station and the times of its archived minute of LEVEL."""
    return served[0], served[1]


@pytest.fixture(scope="module")
def temp_hour(served: tuple[Station, list[float], list[float]]) -> tuple[Station, list[float]]:
    """The station and the times of its archived half hour of TEMP."""
    return served[0], served[2]


Attach = Callable[[Station, str], ConsoleWindow]


def reset(window: ConsoleWindow) -> None:
    """What a test left on a console that the next one could mistake for its own: the message said,
    the answers given for the operator, the windows and faceplates opened, the form shown; hidden
    (nothing painted) until a test attaches it again."""
    window.status.clearMessage()
    vars(window).pop("ask", None)
    window.close_opened()
    window.tabs.setCurrentIndex(0)
    window.hide()


@pytest.fixture
def attach(qtbot) -> Iterator[Attach]:
    """Consoles logged in as users of a station, each with its own config folder: one per user,
    logged in by the first test that asks for it and kept for the module's others (a login is a
    session, its subscriptions and the station's files read), each test leaving it `reset`."""
    used: list[ConsoleWindow] = []

    def open_(station: Station, user: str) -> ConsoleWindow:
        window = station.consoles.get(user)
        if window is None:
            client = ConsoleClient(station.url, folder=station.folder.parent / "consoles" / user, period=0.05)
            try:
                client.discover().result(20)
                client.open(user, user).result(30)
            except Exception:
                client.close()
                raise
            window = station.consoles[user] = ConsoleWindow(StationSource(client))
        window.show()
        used.append(window)
        qtbot.waitUntil(lambda: bool(window.views) and window.views[0].form is not None, timeout=WAIT)
        return window

    try:
        yield open_
    finally:
        for window in used:
            reset(window)


def qualities(window: ConsoleWindow, views: list[FormView] | None = None) -> set[str]:
    """What the elements that show a value of the plant say of it ("" for good), on every form or
    on `views`."""
    return {model.quality for view in (window.views if views is None else views)
            for model in view.form.elements if model.sources()}


def shown(window: ConsoleWindow) -> dict[str, State]:
    """The alarms the console lists, by identity: those not normal."""
    return {r.id: r.state for r in window.source.client.alarms if r.state is not State.NORMAL}


@contextmanager
def readings_of(window: ConsoleWindow) -> Iterator[list[Readings]]:
    """The readings the console takes while in it."""
    seen: list[Readings] = []
    slot = seen.append
    window.source.readings.connect(slot)
    try:
        yield seen
    finally:
        window.source.readings.disconnect(slot)


def test_an_acknowledge_shows_on_the_other_console_and_in_the_journal_a_viewer_is_refused_by_role(
        qtbot, station: Station, attach: Attach) -> None:
    operator, viewer = attach(station, "operator"), attach(station, "viewer")
    station.runtime.simulator_answers(0, False)  # node 0's cable pulled: TRIGGER's quality alarm comes
    try:
        for console in (operator, viewer):
            qtbot.waitUntil(lambda c=console: any(r.id == "TRIGGER.BAD" for r in c.unacknowledged),
                            timeout=WAIT)
        alarm = next(r for r in viewer.unacknowledged if r.id == "TRIGGER.BAD")
        refused: Answer = viewer.acknowledge(alarm).result(20)
        assert str(refused.refusal) == "TRIGGER.BAD: needs the operator role; viewer is viewer"
        qtbot.waitUntil(lambda: "needs the operator role; viewer is viewer" in viewer.status.currentMessage(),
                        timeout=WAIT)
        assert operator.acknowledge(alarm).result(20).ok
        qtbot.waitUntil(lambda: all(r.id != "TRIGGER.BAD" for r in viewer.unacknowledged), timeout=WAIT)
        acked = [r.text or "" for r in station.records if r.kind == "alarm" and r.source == "TRIGGER.BAD"
                 and "квитирована; оператор opcua:operator@127.0.0.1:" in (r.text or "")]
        assert acked, "the acknowledgement journaled with the operator's name"
        qtbot.waitUntil(lambda: not viewer.banner.ack.isEnabled(), timeout=WAIT)  # as the station answers
        assert "needs the operator role; viewer is viewer" in viewer.summary.ack.toolTip()
        assert operator.commands.shelve(operator.who, "TRIGGER.BAD", "cable work", 600).result(20).ok
        rows = viewer.summary
        qtbot.waitUntil(lambda: any(r.id == "TRIGGER.BAD" and r.state is State.SHELVED for r in rows.rows),
                        timeout=WAIT)
        assert operator.commands.unshelve(operator.who, "TRIGGER.BAD").result(20).ok
        journal = viewer.journal  # the station's journal, read over OPC UA, names the operator too
        qtbot.waitUntil(lambda: any(r.kind == "alarm" and "TRIGGER.BAD" in (r.text or "") and
                                    "оператор opcua:operator@" in (r.text or "") for r in journal.model.rows),
                        timeout=WAIT)
    finally:
        station.runtime.simulator_answers(0, True)
    lines = station.runtime.status().consoles
    assert any(line.startswith("operator@127.0.0.1:") for line in lines)
    assert any(line.startswith("viewer@127.0.0.1:") for line in lines)
    assert any("OPC UA: подключился opcua:viewer@127.0.0.1:" in (r.text or "")
               for r in station.records)


def test_a_setpoint_written_on_one_console_shows_on_the_other(
        qtbot, station: Station, attach: Attach) -> None:
    writer, watcher = attach(station, "operator"), attach(station, "viewer")
    watcher.tabs.setCurrentIndex(ANALOG)  # the form that shows the setpoint: the console watches it
    address = station.runtime.symbols["SETPOINT"]
    raw = 1234 if station.runtime.readings().tag("TEMP_SP").raw != 1234 else 2345
    with readings_of(watcher) as seen:
        assert writer.target.write_word(address, raw, user="operator", label="Уставка") is None  # sent
        qtbot.waitUntil(lambda: bool(seen) and seen[-1].tag("TEMP_SP").raw == raw and
                        watcher.source.covered.covers(watcher.reads[ANALOG]), timeout=WAIT)
    written = [r for r in station.records if r.kind == "operator" and "TEMP_SP" in (r.text or "")]
    assert written and (written[-1].source or "").startswith("opcua:operator@")
    watcher.target.write_word(address, 7, user="viewer", label="Уставка")  # refused by the station
    qtbot.waitUntil(lambda: "needs the operator role; viewer is viewer" in watcher.status.currentMessage(),
                    timeout=WAIT)
    program = writer.open_program()  # the Program view on the console's session, as the station lets it
    assert program is not None and program.source.client is writer.client
    step = program.monitor.step_button
    qtbot.waitUntil(lambda: "the station does not let operator do this" in step.toolTip(), timeout=WAIT)
    program.close()
    assert writer.client.error == "" and writer.client.snapshot is not None  # its session goes on
    element = next(m for v in writer.views for m in v.form.elements if isinstance(m, Writer))
    confirm, element.Confirm = element.Confirm, True  # a command that cannot be taken back: asked first
    writer.ask = lambda title, text: False
    try:
        assert element.refused("Уставка = 100") == "cancelled"
    finally:
        element.Confirm = confirm


def watched(station: Station, window: ConsoleWindow) -> Ranges:
    """The parts of the memory the station reports to the console's subscription, as the station's
    monitored items of it say (asyncua's server keeps them by subscription)."""
    server = next(p for p in station.runtime.publishers if hasattr(p, "seats")).server.server
    memory = window.client.memory
    subscription = server.iserver.subscription_service.subscriptions[memory._subscription.subscription_id]
    bits: list[tuple[int, int]] = []
    data: list[tuple[int, int]] = []
    for item in subscription.monitored_item_srv._monitored_items.values():
        read = item.read_value_id
        name = str(read.NodeId.Identifier)
        if name in ("NetPlc.Memory.Bits", "NetPlc.Memory.Data"):
            is_bits = name.endswith("Bits")
            span = numeric_range(read.IndexRange) or (0, (IO_BITS if is_bits else DATA_SIZE) - 1)
            (bits if is_bits else data).append(span)
    return Ranges(tuple(sorted(bits)), tuple(sorted(data)))


def test_a_console_watches_only_what_the_form_shown_reads_and_all_of_it_for_the_program_view(
        qtbot, station: Station, attach: Attach) -> None:
    console = attach(station, "engineer")
    console.tabs.setCurrentIndex(ANALOG)
    analog = console.reads[ANALOG]
    assert 0 < analog.size < 64 and len(analog.bits + analog.data) <= 4  # a few words, a few items
    qtbot.waitUntil(lambda: watched(station, console) == analog, timeout=WAIT)
    shown = {handle for _, handle in console.client.memory._items.values()}  # the analog form's parts
    level = station.runtime.symbols["LEVEL"]  # node 0's simulation moves it: what the console shows
    qtbot.waitUntil(lambda: console.source.covered.covers(analog) and console.client.snapshot is not None
                    and console.client.snapshot.get_word(level) != 0, timeout=WAIT)
    console.tabs.setCurrentIndex(0)  # another form: another set, the one before no more
    qtbot.waitUntil(lambda: watched(station, console) == console.reads[0], timeout=WAIT)
    assert console.reads[0] != analog
    program = console.open_program()
    assert program is not None
    try:
        qtbot.waitUntil(lambda: watched(station, console) == WHOLE, timeout=WAIT)  # it reads any address
    finally:
        program.close()
    qtbot.waitUntil(lambda: watched(station, console) == console.reads[0], timeout=WAIT)
    memory = console.client.memory  # the parts given up are forgotten: no growth at each form switched
    watching = {handle for _, handle in memory._items.values()}
    assert set(memory._apply) >= watching and not (shown - watching) & set(memory._apply)


def test_a_form_changed_at_the_station_reaches_the_console(qtbot, station: Station, attach: Attach) -> None:
    console = attach(station, "viewer")
    form = station.folder / "forms" / "03_sync.hmi"
    doc = json.loads(form.read_text(encoding="utf-8"))
    doc["form"]["title"] = "Changed at the station"
    form.write_text(json.dumps(doc, ensure_ascii=False), encoding="utf-8")
    tabs = console.tabs
    qtbot.waitUntil(lambda: "Changed at the station" in map(tabs.tabText, range(tabs.count())), timeout=WAIT)
    assert len(console.views) == 3


def test_the_station_lists_its_consoles_and_refuses_one_beyond_max_consoles(
        qtbot, station: Station, attach: Attach, tmp_path: Path) -> None:
    attach(station, "operator")
    seats = next(p.seats for p in station.runtime.publishers if hasattr(p, "seats"))
    bar = StationStatusBar()
    qtbot.addWidget(bar)
    bar.show_status(station.runtime.status())
    assert bar.consoles.text() == f"Consoles {len(seats.seats())}"
    assert any(line.startswith("operator@127.0.0.1:") for line in bar.consoles.toolTip().splitlines())
    limit, seats.limit = seats.limit, len(seats.seats())  # as if [opcua] max_consoles said so
    try:
        one_more = ConsoleClient(station.url, folder=tmp_path / "one-more")
        try:
            one_more.discover().result(20)
            with pytest.raises(LoginError, match="BadTooManySessions"):
                one_more.open("viewer", "viewer").result(30)
        finally:
            one_more.close()
    finally:
        seats.limit = limit
    assert any(r.kind == "operator" and "max_consoles" in (r.text or "") and "viewer" in (r.source or "")
               for r in station.records)


def test_a_silence_the_station_took_stops_the_consoles_sound_at_once(
        qtbot, station: Station, attach: Attach) -> None:
    console = attach(station, "operator")
    summary, horn = console.summary, console.source.station_alarms.horn
    node = station.runtime.simulators[0].engine
    node.stop()  # its program moves the level 10 a scan (a triangle wave): held, no transition comes later
    node.write_word(0o4010, 3950)  # LEVEL 96 %: LEVEL.HH, priority 2, sounds until silenced
    try:
        qtbot.waitUntil(lambda: horn.sounding, timeout=WAIT)
        summary.annunciator.tick()
        assert summary.annunciator.sounding
        summary.silence_sound()  # the station's Silence as the console's user
        qtbot.waitUntil(lambda: not summary.annunciator.sounding and not horn.sounding, timeout=WAIT)
        assert any(r.kind == "operator" and "opcua:operator@" in (r.source or "") for r in station.records
                   if "silenced" in (r.text or "") or "звук" in (r.text or ""))
        console.source.station_alarms.show(console.client.alarms)  # the rows again: silenced stays quiet
        summary.annunciator.tick()
        assert not summary.annunciator.sounding and not horn.sounding
    finally:
        node.write_word(0o4010, 0)
        node.start()


def test_the_console_command_wants_an_opc_tcp_url() -> None:
    run = subprocess.run([sys.executable, str(REPO / "main.py"), "console", "http://10.0.0.10/"],
                         capture_output=True, text=True, timeout=60, cwd=REPO)
    assert run.returncode == 2 and run.stderr == "http://10.0.0.10/: not an opc.tcp:// URL\n"


def test_a_consoles_trend_shows_the_stations_archived_values_of_a_stored_tag(
        qtbot, archived: tuple[Station, list[float]], attach: Attach) -> None:
    station, times = archived
    if dt.date.fromtimestamp(times[0]) != dt.date.today():
        pytest.skip("the archived minute is of yesterday (a run at midnight)")
    window = attach(station, "viewer")
    trend = next(t for view in window.views for t in view.trends  # the analog form's LEVEL graph
                 if isinstance(t.model, AnalogBase))
    qtbot.waitUntil(lambda: len(trend.hist_times) >= len(times), timeout=WAIT)
    shown = dict(zip(trend.hist_times.tolist(), trend.hist_values.tolist()))
    for k, ts in enumerate(times):
        value = next(v for s, v in shown.items() if abs(s - ts) < 1e-3)
        if k == 50:
            assert math.isnan(value)  # the gap
        else:
            assert value == pytest.approx(40 * k * 100 / 4095, abs=0.01)  # LEVEL in %


def test_the_consoles_trend_window_draws_a_stored_tag_from_the_stations_history(
        qtbot, archived: tuple[Station, list[float]], attach: Attach, tmp_path: Path) -> None:
    station, times = archived
    console = attach(station, "operator")
    trend = console.open_trends()
    assert trend is not None
    trend.search.setText("уровень")  # the station's tags, searched as at the workstation
    assert [trend.tag_list.item(i).data(Qt.ItemDataRole.UserRole) for i in range(trend.tag_list.count())] \
        == ["LEVEL"]
    pen = trend.add_pen("LEVEL")
    assert pen is not None
    level = ranges_of([(station.runtime.symbols["LEVEL"], 2)])  # watched for its live values
    qtbot.waitUntil(lambda: watched(station, console).covers(level), timeout=WAIT)
    trend.set_range(times[0] - 5, times[-1] + 5)
    qtbot.waitUntil(lambda: not trend.loading() and any(len(ts) for ts, _ in pen.days.values()), timeout=WAIT)
    ts, values = pen.samples()
    shown = dict(zip(ts.tolist(), values.tolist()))
    for k in (0, 1, 49, 51, 99):  # the station's physical values, back to the archive's words, converted
        value = next(v for s, v in shown.items() if abs(s - times[k]) < 1e-3)
        assert value == pytest.approx(40 * k * 100 / 4095, abs=0.01)
    assert math.isnan(next(v for s, v in shown.items() if abs(s - times[50]) < 1e-3))  # the gap
    trend.set_cursors(times[10], times[90])
    trend.dirty = True
    trend.redraw()
    assert trend.cell("LEVEL", "B − A") == f"{40 * 80 * 100 / 4095:.1f}"
    qtbot.waitUntil(lambda: len(pen.live_t) >= 2, timeout=WAIT)  # the station's live values go on
    trend.save_as("Уровни")  # kept in the console's own folder for the station, per user
    assert console.client.keep.joinpath("trends.json").is_file()
    trend.export_csv(tmp_path / "trend.csv")
    assert len((tmp_path / "trend.csv").read_text(encoding="utf-8").splitlines()) > 90
    trend.export_png(tmp_path / "trend.png")
    assert (tmp_path / "trend.png").stat().st_size > 0
    trend.close()
    shown = console.reads[console.tabs.currentIndex()]
    assert console.client.wanted == shown  # the window's want went with it
    again = console.open_trends()
    assert again is not None and again.open_trend("Уровни") and list(again.pens) == ["LEVEL"]


def test_the_consoles_viewer_queries_the_stations_journal_and_series(
        qtbot, archived: tuple[Station, list[float]], attach: Attach, tmp_path: Path) -> None:
    station, times = archived
    console = attach(station, "viewer")
    viewer = console.open_viewer()
    assert viewer is not None and viewer.day == dt.date.fromtimestamp(times[0])

    def texts() -> list[str]:
        qtbot.waitUntil(lambda: viewer.paging is None, timeout=WAIT)
        return [r.text or "" for r in viewer.model.rows]

    def between(first: float, last: float) -> None:
        for edit, ts in ((viewer.since, first), (viewer.until, last)):
            edit.setTime(QTime.fromString(dt.datetime.fromtimestamp(ts).strftime("%H:%M:%S"), "HH:mm:ss"))

    assert {"Насос 2 остановлен", "Насос 2 в работе", "write Уставка: 1 -> 2"} <= set(texts())
    assert not viewer.group.isEnabled()  # a message's group is not in its event
    between(times[0] - 1, times[-1] + 1)  # the archived minute: the station's own records came after it
    viewer.text.setText("НАСОС")  # contains, in the spellings the local archive tries: by the station
    viewer.apply_filter()
    assert texts() == ["Насос 2 остановлен", "Насос 2 в работе"]
    viewer.type.setCurrentIndex(3)  # 2 alarm and above
    viewer.apply_filter()
    assert texts() == ["Насос 2 остановлен"] and viewer.page_label.text() == "records 1–1 of 1"
    viewer.text.clear()
    viewer.type.setCurrentIndex(0)
    viewer.kind.setCurrentText("operator")
    viewer.apply_filter()
    assert texts() == ["write Уставка: 1 -> 2"]
    viewer.kind.setCurrentText("all")
    between(times[15], times[40])
    viewer.apply_filter()
    assert "Насос 2 остановлен" not in texts() and "Насос 2 в работе" in texts()
    assert viewer.export_csv(tmp_path / "journal.csv") == len(texts())
    between(times[0] - 1, times[-1] + 1)
    labels = [viewer.series_list.item(i).text() for i in range(viewer.series_list.count())]
    level = next(i for i, label in enumerate(labels) if label.startswith("LEVEL"))
    assert labels[level] == "LEVEL Уровень, % (04010)"
    viewer.check_series(level)
    qtbot.waitUntil(lambda: not viewer.loading and len(viewer.curves) == 1, timeout=WAIT)
    xs, ys = next(iter(viewer.curves.values())).getData()
    assert len(xs) >= 100 and np.nanmax(ys) == pytest.approx(40 * 99 * 100 / 4095, abs=0.01)
    assert np.isnan(ys).any()  # the gap


# --- a tag's faceplate at a remote console: the workstation's own faceplate, opened from the same
# elements, its data the station's (the tag's part of the memory watched while it is open, the hour
# from the station's Historical Access, the alarms as the console lists them) and every action the
# station's command as the console's user

SETPOINT = 0o4030  # TEMP_SP's word (0..4095 raw = -50..150 °C)


def open_plate(qtbot, window: ConsoleWindow, name: str) -> Faceplate:
    """The faceplate of the element `name` of the analog form, opened as an operator does."""
    window.tabs.setCurrentIndex(ANALOG)
    _, widget = element(window, name)  # type: ignore[arg-type]
    qtbot.mouseDClick(widget, Qt.MouseButton.LeftButton)
    assert window.faceplates is not None
    tag = window.faceplates.bound[widget]
    plate = window.faceplates.open[tag.name]
    assert plate.isVisible()
    return plate


def test_the_consoles_faceplate_shows_the_stations_value_and_hour_and_watches_its_tag_while_open(
        qtbot, temp_hour: tuple[Station, list[float]], attach: Attach) -> None:
    st, times = temp_hour
    console = attach(st, "viewer")
    plate = open_plate(qtbot, console, "Температура")
    temp = plate.tag
    assert temp.name == "TEMP" and set(plate.alarm_rows) == {"TEMP.HH", "TEMP.H", "TEMP.BAD"}
    qtbot.waitUntil(lambda: plate.quality.text() == "good" and plate.value.text() == temp.format(
        st.runtime.readings().tag("TEMP").value), timeout=WAIT)  # the station's value, with its unit
    assert plate.value.text().endswith(" °C")
    if time.time() - times[0] < 3600:  # (the hour read from the station's history)
        qtbot.waitUntil(lambda: np.isin(np.round(times, 3), np.round(plate.times, 3)).all(), timeout=WAIT)
        at = np.isin(np.round(plate.times, 3), np.round(times, 3))
        assert plate.values[at] == pytest.approx(50.0)
    qtbot.waitUntil(lambda: plate.points() >= len(times) + 2, timeout=WAIT)  # the hour, then live
    assert plate.set.isHidden()  # a measurement: no form sets it, nor does its faceplate
    qtbot.waitUntil(lambda: not plate.force.isEnabled(), timeout=WAIT)  # as the station answers

    operand = ranges_of([temp.operand])
    console.tabs.setCurrentIndex(0)  # a form without TEMP: the open faceplate keeps it watched
    qtbot.waitUntil(lambda: watched(st, console) == console.reads[0] | operand, timeout=WAIT)
    shown = len(plate.live_t)
    qtbot.waitUntil(lambda: len(plate.live_t) > shown, timeout=WAIT)  # and live
    plate.close()
    qtbot.waitUntil(lambda: watched(st, console) == console.reads[0], timeout=WAIT)  # released
    assert console.client.wanted == console.reads[0]


def test_the_consoles_faceplate_sets_forces_and_unforces_as_the_user_at_the_station_a_viewer_is_refused(
        qtbot, station: Station, attach: Attach) -> None:
    st = station
    engine = st.runtime.engine
    assert engine is not None
    viewer = attach(st, "viewer")
    plate = open_plate(qtbot, viewer, "Уставка температуры")
    assert plate.tag.name == "TEMP_SP" and not plate.set.isHidden()
    qtbot.waitUntil(lambda: not plate.set.isEnabled() and not plate.entry.isEnabled(), timeout=WAIT)
    assert "needs the operator role" in plate.set.toolTip()
    plate.entry.setText("50")  # were it sent, the station refuses it
    plate.set_value()
    qtbot.waitUntil(lambda: "needs the operator role; viewer is viewer" in plate.message.text(), timeout=WAIT)
    assert engine.snapshot.get_word(SETPOINT) != round(100 / 200 * 4095)

    reset(viewer)  # done with: hidden, it no longer paints its forms and faceplate at each scan
    operator = attach(st, "operator")
    plate = open_plate(qtbot, operator, "Уставка температуры")
    qtbot.waitUntil(lambda: plate.set.isEnabled(), timeout=WAIT)
    plate.entry.setText("50")
    plate.set_value()
    qtbot.waitUntil(lambda: engine.snapshot.get_word(SETPOINT) == round(100 / 200 * 4095), timeout=WAIT)
    written = [r for r in st.records if r.kind == "operator" and (r.text or "").startswith("запись ")
               and "TEMP_SP" in (r.text or "")]
    assert written and (written[-1].source or "").startswith("opcua:operator@")
    assert "-> 50.0 °C" in (written[-1].text or "")
    qtbot.waitUntil(lambda: plate.value.text() == "50.0 °C", timeout=WAIT)  # shown back from the station
    plate.entry.setText("900")  # outside PhyMin..PhyMax: the station refuses it
    plate.set_value()
    # Bad_OutOfRange carries no text: the console says it as the station's layer does, with the range
    qtbot.waitUntil(lambda: "900.0 вне диапазона -50.0 °C .. 150.0 °C" in plate.message.text(), timeout=WAIT)
    assert not plate.force.isEnabled()

    reset(operator)
    engineer = attach(st, "engineer")
    plate = open_plate(qtbot, engineer, "Уставка температуры")
    qtbot.waitUntil(lambda: plate.force.isEnabled(), timeout=WAIT)
    engineer.ask = asked = Answers(True)
    plate.force_entry.setText("20")
    plate.force_value()
    assert asked.asked[-1].startswith("Force: Force TEMP_SP to 20.0 °C?")
    qtbot.waitUntil(lambda: plate.forced.text().startswith("F forced by opcua:engineer@")
                    and plate.value.text() == "20.0 °C", timeout=WAIT)
    forced = [r for r in st.records if r.kind == "operator" and (r.text or "").startswith("фиксация TEMP_SP")]
    assert forced and (forced[-1].source or "").startswith("opcua:engineer@")
    plate.unforce_value()
    qtbot.waitUntil(lambda: plate.forced.text() == "", timeout=WAIT)
    assert engine.forces.count == 0


def test_a_console_shows_the_station_unreachable_and_reconnects_by_itself(
        qtbot, station: Station, attach: Attach) -> None:
    """Last of the module: it stops the station, and leaves it restarted."""
    console = attach(station, "operator")
    qtbot.waitUntil(lambda: qualities(console) == {""}, timeout=WAIT)
    station.stop()
    qtbot.waitUntil(lambda: qualities(console) == {Quality.UNREACHABLE.word}, timeout=WAIT)
    assert console.health.isVisible() and "station unreachable" in console.health.problems[0]
    station.restart()
    shown_view = console.views[console.tabs.currentIndex()]  # refreshed while shown; others once shown
    qtbot.waitUntil(lambda: qualities(console, [shown_view]) == {""} and not console.client.error,
                    timeout=WAIT)
    assert not console.health.isVisible()
    console.tabs.setCurrentIndex(ANALOG)
    qtbot.waitUntil(lambda: qualities(console, [console.views[ANALOG]]) == {""}, timeout=WAIT)
    qtbot.waitUntil(lambda: shown(console) == {r.id: r.state for r in station.runtime.alarms.summary},
                    timeout=WAIT)  # the station's alarms as they are now
