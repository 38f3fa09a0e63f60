"""The alarm summary and banner over a real alarm system and the command layer over a real engine
(stepped: an action is applied at the next scan): order, colours and blinking, counts, filter,
acknowledge selected / all with one record each naming the alarm and the user, shelving with
duration and reason, the sound of priorities 1-2, and what a viewer may not do."""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterator
from pathlib import Path

import pytest
from PySide6.QtCore import Qt

from app.authority import Commands, Reason, Source, Who
from app.gui.alarm_health import HealthDialog, health_text
from app.gui.alarm_summary import AlarmSummary, row_colours
from app.gui.alarms import AlarmBanner
from app.gui.annunciation import Annunciation, QSoundEffect
from app.gui.sounds import shipped
from app.scada.alarms import AlarmRow, State
from app.scada.horn import Horn
from app.scada.station import StationAlarms
from hmi_forms.widgets.records import type_name
from netplc.engine import Engine, FakeClock
from netplc.memory import Memory
from netplc.program import parse
from netplc.records import ListSink
from registrar.query import Row

TAGS = ("name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals,description,h,priority\n"
        "LEVEL,04010,word,%,0,4095,0,100,1,Уровень,90,2\n"
        "TEMP,04012,word,°C,0,1000,-50,150,1,Температура,120,3\n")
T0 = 1_800_000_000.0
ROLES = {"ivanov": "operator", "petrov": "operator", "vera": "viewer"}


class Station:
    def __init__(self, folder: Path) -> None:
        (folder / "tags.csv").write_text(TAGS, encoding="utf-8")
        self.sink = ListSink()
        self.alarms = StationAlarms(folder / "tags.csv", parse("JMP 0\n"), [], self.sink,
                                    folder / "alarms.sqlite")
        self.clock = FakeClock()
        self.engine = Engine(parse("JMP 0\n"), clock=self.clock, sink=self.sink)
        self.commands = Commands(self.engine, self.sink, role_of=ROLES.get, alarms=self.alarms)
        self.mem = Memory()
        self.scan = 0

    def summary(self, user: str) -> AlarmSummary:
        return AlarmSummary(self.alarms, self.commands, lambda: Who(user, Source.CONSOLE))

    def apply(self) -> None:
        """The engine's next scan: the commands queued are applied (and answered)."""
        self.clock.advance(self.engine.tick)
        self.engine.scan()

    def step(self, level: int, temp: int, at: float) -> None:
        self.mem.set_word(0o4010, level)
        self.mem.set_word(0o4012, temp)
        self.scan += 1
        self.alarms.on_scan(self.mem.snapshot(self.scan, at - T0, at, "running"))

    def alarm_records(self) -> list[tuple[str, int, int, str]]:
        return [(r.source, r.number, r.type, r.text) for r in self.sink.records if r.kind == "alarm"]


@pytest.fixture
def station(tmp_path: Path) -> Iterator[Station]:
    s = Station(tmp_path)
    yield s
    s.alarms.close()


def test_listed_by_priority_then_time_with_counts_colours_and_filter(qtbot, station: Station) -> None:
    station.step(4000, 900, T0)  # both high: LEVEL.H (priority 2), TEMP.H (priority 3)
    summary = station.summary("ivanov")
    qtbot.addWidget(summary)
    assert [r.id for r in summary.model.rows] == ["LEVEL.H", "TEMP.H"]
    assert [summary.counts[p].text() for p in (1, 2, 3, 4)] == [
        "P1 critical: 0", "P2 high: 1", "P3 medium: 1", "P4 low: 0"]
    level = summary.model.rows[0]
    assert level.shown == "97.7 %" and level.state is State.UNACK
    assert row_colours(level, True) != row_colours(level, False)  # unacknowledged blinks
    summary.filter.setText("темп")
    assert [r.id for r in summary.model.rows] == ["TEMP.H"]
    summary.filter.clear()
    summary.resize(900, 200)
    assert not summary.grab().isNull()


def test_acknowledge_selected_and_all_one_record_each_naming_alarm_and_user(qtbot, station: Station) -> None:
    station.step(4000, 900, T0)
    summary = station.summary("ivanov")
    qtbot.addWidget(summary)
    summary.table.selectRow(1)  # TEMP.H
    summary.acknowledge_selected()
    station.apply()
    summary.refresh()
    assert station.alarms.system.get("TEMP.H").state is State.ACKED
    assert station.alarms.system.get("LEVEL.H").state is State.UNACK
    station.step(0, 0, T0 + 5)  # both return; LEVEL.H is still unacknowledged
    summary.refresh()
    assert [(r.id, r.state) for r in summary.unacknowledged()] == [("LEVEL.H", State.RTNUN)]
    before = len(station.alarm_records())
    summary.acknowledge_all()
    station.apply()
    summary.refresh()
    new = station.alarm_records()[before:]
    assert len(new) == 1 and new[0][0] == "LEVEL.H" and "by ivanov" in new[0][3]
    assert not summary.unacknowledged() and summary.model.rows == []


def test_shelve_needs_a_reason_and_comes_back_by_itself(qtbot, station: Station) -> None:
    station.step(4000, 0, T0)
    summary = station.summary("petrov")
    qtbot.addWidget(summary)
    answers: list[tuple[str, Reason]] = []
    summary.answers.answered.connect(lambda what, answer: answers.append((what, answer.reason)))
    summary.shelve_alarm("LEVEL.H", 10, " ")
    assert answers == [("Shelve LEVEL.H", Reason.INVALID)]  # refused by the layer: a reason is needed
    summary.shelve_alarm("LEVEL.H", 10, "датчик на поверке")
    station.apply()
    assert answers[-1] == ("Shelve LEVEL.H", Reason.APPLIED)
    summary.refresh()
    row = summary.model.rows[0]
    assert row.state is State.SHELVED and row.shelved_by == "petrov" and row.reason == "датчик на поверке"
    assert summary.counts[2].text() == "P2 high: 0"  # shelved alarms are not counted as listed
    assert "shelved by petrov" in summary.model.data(summary.model.index(0, 5))  # the widest column
    station.step(4000, 0, T0 + 10 * 60 + 1)  # the shelving has run out, the level is still high
    summary.refresh()
    assert summary.model.rows[0].state is State.UNACK


def test_the_banner_shows_the_highest_priority_unacknowledged_alarm(qtbot, station: Station) -> None:
    station.step(0, 900, T0)  # TEMP.H, priority 3
    station.step(4000, 900, T0 + 1)  # LEVEL.H, priority 2, after it
    summary = station.summary("ivanov")
    banner = AlarmBanner()
    qtbot.addWidget(summary)
    qtbot.addWidget(banner)
    banner.show_alarms(summary.unacknowledged())
    assert "LEVEL.H" in banner.text.text() and "P2" in banner.text.text()
    assert banner.count.text() == "2" and banner.count.toolTip() == "2 unacknowledged"


def test_priority_1_and_2_sound_until_acknowledged_or_silenced(qapp, tmp_path: Path) -> None:
    """The station's horn, and the console's sound of it: the file of the priority that sounds,
    in a loop (or a beep a second where Qt Multimedia is not installed)."""
    beeps: list[int] = []
    horn = Horn()
    mine = tmp_path / "klaxon.wav"
    sound = Annunciation(horn, True, (mine, None), lambda: beeps.append(1))
    high = AlarmRow("LEVEL.H", 2, State.UNACK, T0, T0, 97.0, "high")
    medium = AlarmRow("TEMP.H", 3, State.UNACK, T0, T0, 130.0, "high")
    assert not horn.update([medium])
    sound.tick()
    assert not sound.sounding and sound.playing is None and beeps == []
    assert horn.update([high, medium]) and horn.priority == 2
    sound.tick()
    assert sound.sounding and sound.playing == shipped(2)  # the shipped WAV of priority 2
    assert beeps == ([1] if QSoundEffect is None else [])
    horn.silence(T0 + 1)
    horn.update([high])
    sound.tick()
    assert not horn.sounding and sound.playing is None  # silenced: only a newer alarm sounds again
    horn.update([AlarmRow("LEVEL.HH", 1, State.UNACK, T0 + 2, T0 + 2, 99.0, "hh")])
    sound.tick()
    assert horn.priority == 1 and sound.playing == mine  # station.toml's alarm_sound_p1
    horn.update([AlarmRow("LEVEL.HH", 1, State.ACKED, T0 + 2, T0 + 3, 99.0, "hh")])
    sound.tick()
    assert not horn.sounding and sound.playing is None  # acknowledged
    horn.update([AlarmRow("X", 1, State.UNACK, T0 + 4, T0 + 4, None, "x")])
    off = Annunciation(horn, False, beep=lambda: beeps.append(1))
    off.tick()
    assert horn.sounding and not off.sounding and off.playing is None  # alarm_sound = false
    assert all(shipped(p).stat().st_size > 1000 for p in (1, 2))


def test_the_horn_bit_follows_the_alarms_and_the_silence(tmp_path: Path) -> None:
    """`alarm_horn`: the bit the program reads to drive a real horn, set while anything sounds."""
    from netplc.memory import Memory

    mem = Memory()
    horn = Horn(bit=0o40060)
    horn.update([AlarmRow("LEVEL.H", 2, State.UNACK, T0, T0, 97.0, "high")])
    horn.write(mem)
    assert mem.get_hmi_bit(0o40060) == 1
    horn.silence(T0 + 1)
    horn.write(mem)
    assert mem.get_hmi_bit(0o40060) == 0


def test_journals_name_an_alarm_records_new_state() -> None:
    row = Row(1, T0, "alarm", 2, int(State.UNACK), "LEVEL.H", int(State.NORMAL), 97.0, "LEVEL.H ...")
    assert type_name(row) == "active-unacknowledged"
    assert type_name(Row(2, T0, "message", 1, 2, None, 3, None, "x")) == "alarm"  # a message's type


def test_the_health_dialog_shows_the_report_of_a_chosen_day(qtbot, headless_archive, tmp_path: Path) -> None:
    dialog = HealthDialog(headless_archive[0])
    qtbot.addWidget(dialog)
    qtbot.waitUntil(lambda: dialog.report.toPlainText().startswith("alarm-system"), timeout=10_000)
    text = dialog.report.toPlainText()  # read in the dialog's worker thread
    assert text.startswith(f"alarm-system health for {dt.date.today():%d.%m.%Y}") and "chattering" in text
    assert health_text(tmp_path / "none.sqlite", dt.date.today()).startswith("no alarm-system health")


def test_a_viewer_finds_every_action_greyed_naming_the_role_and_is_refused_once_a_minute(
        qtbot, station: Station) -> None:
    station.step(4000, 900, T0)
    summary = station.summary("vera")
    qtbot.addWidget(summary)
    summary.annunciator.sounding = True
    summary.refresh()
    for button in (summary.ack, summary.ack_all, summary.shelve, summary.unshelve, summary.silence):
        assert not button.isEnabled(), button.text()
        assert "needs the operator role; vera is viewer" in button.toolTip()
    refused: list[str] = []
    summary.answers.answered.connect(lambda what, answer: refused.append(what) if not answer.ok else None)
    for _ in range(3):  # the layer refuses it all the same when asked directly
        summary.acknowledge_all()
        summary.shelve_alarm("LEVEL.H", 10, "на поверке")
        summary.silence_sound()
    station.apply()
    assert refused == ["Acknowledge all", "Shelve LEVEL.H", "Silence"] * 3
    assert station.alarms.system.get("LEVEL.H").state is State.UNACK and summary.annunciator.sounding
    texts = [r.text for r in station.sink.records if r.kind == "operator"]
    assert [t.split(":")[0] for t in texts] == ["refused acknowledge all", "refused shelve LEVEL.H",
                                                "refused silence"]  # one record per cause per minute
    assert all(r.source == "vera" for r in station.sink.records if r.kind == "operator")


def test_an_operator_acknowledges_and_silences_from_the_summary(qtbot, station: Station) -> None:
    station.step(4000, 900, T0)
    summary = station.summary("ivanov")
    qtbot.addWidget(summary)
    summary.annunciator.sounding = True
    summary.refresh()
    assert summary.ack_all.isEnabled() and summary.silence.isEnabled() and summary.ack_all.toolTip() == ""
    qtbot.mouseClick(summary.silence, Qt.MouseButton.LeftButton)
    qtbot.mouseClick(summary.ack_all, Qt.MouseButton.LeftButton)
    assert summary.annunciator.sounding  # not before the layer has answered
    station.apply()
    qtbot.waitUntil(lambda: not summary.annunciator.sounding)
    assert not summary.silence.isEnabled() and "Stop the sound" in summary.silence.toolTip()
    assert station.alarms.system.get("LEVEL.H").state is State.ACKED
    assert ("ivanov", "alarm sound silenced") in [(r.source, r.text) for r in station.sink.records]


def test_the_alarm_column_says_what_and_the_shelve_dialog_insists_on_a_reason(qtbot,
                                                                              station: Station) -> None:
    from app.gui.alarm_summary import ShelveDialog

    station.step(4000, 0, T0)
    summary = station.summary("petrov")
    qtbot.addWidget(summary)
    model = summary.model
    assert model.data(model.index(0, 2)) == "Уровень"  # the tag's description, not LEVEL.H
    assert model.data(model.index(0, 2), Qt.ItemDataRole.ToolTipRole) == "LEVEL.H"
    assert model.headerData(4, Qt.Orientation.Horizontal) == "Value at change"
    assert "not the value now" in model.headerData(4, Qt.Orientation.Horizontal, Qt.ItemDataRole.ToolTipRole)
    dialog = ShelveDialog("LEVEL.H", summary)
    dialog.show()
    dialog.accept()  # OK with no reason: said, and the dialog stays
    assert dialog.isVisible() and dialog.result() != dialog.DialogCode.Accepted
    assert dialog.missing.isVisibleTo(dialog)
    dialog.presets.activated.emit(1)
    assert dialog.reason.text() == "Maintenance of the instrument" and not dialog.missing.isVisibleTo(dialog)
    dialog.accept()
    assert dialog.result() == dialog.DialogCode.Accepted
