"""The Program view: the listing with live states, the watch table (writes journaled with the user),
forcing and single scans from the view, find / go to label / uses; and the remote monitor against
a real station over a loopback Modbus port: it watches, and is read-only (Modbus has no users)."""

from __future__ import annotations

import socket
import time
from pathlib import Path

import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QApplication, QMenu

from app.authority import Source as Seat
from app.authority import Who
from app.authority.users import Users
from app.gui.monitor.listing import Listing, fmt_value, parse_value, parse_watch
from app.gui.monitor.source import READ_ONLY, LocalSource, RemoteSource
from app.gui.monitor.view import ON, ProgramMonitor, parse_force
from app.gui.monitor.window import ProgramWindow, remote_source
from app.station.config import load_station
from app.station.runtime import Runtime
from netplc.memory import Memory
from netplc.problems import Problems
from netplc.program import parse
from netplc.records import Record
from tests.app.conftest import write_station
from tests.cheap_users import CHEAP, cheap_demo_users

PROGRAM = """; the monitor's test program
TNA $00000
TNA $00001
YON PUMP
TNA $00002
TIM $03000 N:50
TNA $00003
CTR $03010 N:5
loop: TNA PUMP
JMN end
TNA $03760
FON C:$02100 N:MOV S:$04000 D:$04002
end: NOP
"""
SYMBOLS = "name,address,comment\nPUMP,02000,pump\nLEVEL,04000,level\n"


def station(folder: Path, port: int = 0) -> Path:
    """Users eng1 engineer, olga operator and vera viewer (each password the name), at the tests'
    cheap scrypt cost (tests/cheap_users.py)."""
    toml = (f'NetPlcProgram = "p.stl"\nSymbols = "s.csv"\nNetSyncTime = 20\n'
            f'[modbus_server]\nport = {port}\nwritable = [["00000", "02177"], ["04000", "04777"]]\n')
    write_station(folder, toml, {"p.stl": PROGRAM, "s.csv": SYMBOLS})
    users = Users(folder)
    for name, role in (("eng1", "engineer"), ("olga", "operator"), ("vera", "viewer")):
        users.add(name, role, name, CHEAP)
    return folder


@pytest.fixture
def runtime(tmp_path: Path):
    rt = Runtime(load_station(station(tmp_path / "st")))
    records: list[Record] = []
    rt.subscribe(records.append)
    rt.records = records  # type: ignore[attr-defined]
    rt.start()
    yield rt
    rt.stop()


def wait(qtbot, what, timeout: int = 5000) -> None:
    qtbot.waitUntil(what, timeout=timeout)


def operator_texts(rt: Runtime) -> list[tuple[str, str]]:
    return [(r.source or "", r.text or "") for r in rt.records if r.kind == "operator"]  # type: ignore[attr-defined]


# --- the Qt-free part -------------------------------------------------------------------------------


def test_listing_rows_labels_chain_results_and_uses(tmp_path: Path) -> None:
    path = tmp_path / "p.stl"
    path.write_text(PROGRAM, encoding="utf-8")
    program = parse(PROGRAM, source=str(path), symbols={"PUMP": 0o2000})
    listing = Listing(program)
    assert len(listing) == PROGRAM.count("\n") and listing.rows[0].instr is None
    assert listing.labels == {"loop": 8, "end": 12}
    mem = Memory()
    mem.bits[0] = 1
    assert listing.chain(mem, 0) == 1 and listing.chain(mem, 1) == 0  # TNA 0 = 1, then TNA 1 = 0
    mem.bits[1] = 1
    assert listing.chain(mem, 2) == 1  # YON sees RES = 1
    assert [listing.rows[r].line for r in listing.uses(0o2000)] == [4, 9]  # YON PUMP, TNA PUMP
    assert [listing.rows[r].line for r in listing.uses(0o4003)] == [12]  # inside the MOV's D word
    assert listing.find("jmn") == 9 and listing.find("nothing") is None
    assert listing.find("TNA", after=9) == 10  # the next one, wrapping


def test_watch_entries_values_and_formats() -> None:
    symbols = {"PUMP": 0o2000, "LEVEL": 0o4000}
    assert (parse_watch("PUMP", symbols).kind, parse_watch("LEVEL", symbols).kind) == ("bit", "word")
    assert parse_watch("040042", {}).addr == 0o40042
    assert parse_watch("04001:b", {}).kind == "byte" and parse_watch("02000:w", {}).kind == "word"
    with pytest.raises(ValueError, match="neither an octal address nor a symbol"):
        parse_watch("NOPE", symbols)
    with pytest.raises(ValueError, match="010000"):
        parse_watch("010000", {})
    assert parse_value("0x1F", "word") == 31 and parse_value("1Fh", "byte") == 31
    assert parse_value("7", "word") == 7
    with pytest.raises(ValueError, match="does not fit a bit"):
        parse_value("2", "bit")
    assert [fmt_value(0x1234, f) for f in ("hex", "dec", "BCD")] == ["1234h", "4660", "1234"]
    assert fmt_value(0x12AB, "BCD") == "----"


# --- the view on the local runtime ------------------------------------------------------------------


def test_the_view_renders_the_listing_with_live_states(qtbot, runtime: Runtime, tmp_path: Path) -> None:
    monitor = ProgramMonitor(LocalSource(runtime), lambda: "engineer")
    qtbot.addWidget(monitor)
    monitor.resize(1366, 768)
    monitor.show()
    engine = runtime.engine
    assert engine is not None
    engine.write_bit(0, 1, user="test")
    engine.write_bit(1, 1, user="test")
    engine.write_word(0o4000, 0x0042, user="test")
    wait(qtbot, lambda: engine.snapshot.get_word(0o4002) == 0x0042)
    wait(qtbot, lambda: monitor.view.snapshot is not None and monitor.view.snapshot.get_word(0o4002) == 0x42)
    image = monitor.view.viewport().grab().toImage()
    view = monitor.view
    row = 3  # line 4: YON PUMP, bit 1 and RES 1
    y = row * view.line_h + view.line_h // 2
    assert image.pixelColor(6 * view.char_w + 3, y) == ON
    assert image.pixelColor(9 * view.char_w + 3, y) == ON
    assert 0 < view.painted_rows <= len(view.listing)
    assert monitor.forced_pill.text() == "F: 0 forced"
    monitor.grab().save(str(tmp_path / "monitor.png"))
    # FON values: the MOV's S and D words in the listing, in the chosen format
    assert view._values(view.listing.rows[11].instr, view.snapshot) == "out 000 S=0042h D=0042h"
    monitor.formats.setCurrentText("dec")
    assert view._values(view.listing.rows[11].instr, view.snapshot).endswith("S=66 D=66")


def test_a_2000_line_listing_paints_only_the_lines_on_screen(qtbot, tmp_path: Path) -> None:
    text = "".join(f"TNA ${k % 0o2000:05o}\nYON ${0o2000 + k % 0o1000:05o}\n" for k in range(1000))
    path = tmp_path / "big.stl"
    path.write_text(text, encoding="utf-8")

    class Still:  # a source that never changes: only the painting is looked at
        title, symbols, tags = "big", {}, {}
        read_only, acting = "still", None
        program = parse(text, source=str(path))
        snap = Memory().snapshot()

        def snapshot(self):
            return self.snap

        def state(self) -> str:
            return "stopped"

        def forces(self):
            return ()

        def need(self, addrs) -> None:
            list(addrs)

        def timer(self, c):
            return 0.0

        counter = timer

    monitor = ProgramMonitor(Still(), lambda: "engineer")  # type: ignore[arg-type]
    qtbot.addWidget(monitor)
    monitor.resize(1366, 768)
    monitor.show()
    assert len(monitor.listing) == 2000
    monitor.view.viewport().grab()
    assert 20 < monitor.view.painted_rows < 60
    monitor.view.go_to(1500)
    monitor.view.viewport().grab()
    assert 1500 in monitor.view.visible_rows() and monitor.view.painted_rows < 60
    refreshes = monitor.refreshes
    monitor.refresh()
    assert monitor.refreshes == refreshes  # the same snapshot: nothing redrawn


def test_watch_edit_force_unforce_and_step_from_the_view(qtbot, runtime: Runtime) -> None:
    monitor = ProgramMonitor(LocalSource(runtime), lambda: "eng1")
    qtbot.addWidget(monitor)
    engine = runtime.engine
    assert engine is not None
    monitor.watch.item(0, 0).setText("LEVEL")  # typed into the empty row
    assert monitor.watch_items[0].addr == 0o4000 and monitor.watch.rowCount() == 2
    monitor.watch.item(1, 0).setText("NOPE")
    assert "NOPE" in monitor.message.text() and len(monitor.watch_items) == 1
    monitor.watch.item(0, 1).setText("0x123")  # an edit is a write
    wait(qtbot, lambda: engine.snapshot.get_word(0o4000) == 0x123)
    wait(qtbot, lambda: monitor.watch.item(0, 2).text() == "0123h")
    assert ("program view:eng1", "write 04000: 0 -> 291") in operator_texts(runtime)
    monitor.force("word", 0o4000, 7)
    monitor.force("bit", 0o2000, None)  # bumpless
    wait(qtbot, lambda: monitor.forced_pill.text() == "F: 2 forced")
    monitor.watch.item(0, 1).setText("9")  # a write loses to the force
    wait(qtbot, lambda: monitor.watch.item(0, 4).text() == "F 7 (program view:eng1)")
    assert engine.snapshot.get_word(0o4000) == 7
    asked: list[str] = []
    monitor.ask = lambda title, text: asked.append(text) is None and len(asked) > 1  # no, then yes
    monitor.unforce_button.click()
    assert asked[0].startswith("Unforce all 2 forces? The memory keeps the forced values")
    assert monitor.forced_pill.text() == "F: 2 forced"  # answered no: nothing sent
    monitor.unforce_button.click()
    wait(qtbot, lambda: monitor.forced_pill.text() == "F: 0 forced")
    texts = operator_texts(runtime)
    assert ("program view:eng1", "unforce 04000:word (was forced 7; unforce all)") in texts
    assert ("program view:eng1", "force 02000: 0 -> 0 (bumpless)") in texts
    monitor.step()  # running: refused, said so
    assert monitor.message.text() == "Refused: Step one scan: NetPlc is running: stop it to step one scan"
    runtime.stop_program("eng1")
    wait(qtbot, lambda: engine.snapshot.state.startswith("stopped"))
    before = engine.scan_counter
    monitor.step_button.click()
    assert engine.scan_counter > before and monitor.view.snapshot is engine.snapshot
    assert any(t.startswith("step one scan") for _, t in operator_texts(runtime))
    wait(qtbot, lambda: monitor.message.text() == "")  # the stale refusal goes with a successful step


def test_find_go_to_label_and_follow_a_symbol(qtbot, runtime: Runtime) -> None:
    monitor = ProgramMonitor(LocalSource(runtime), lambda: "eng1")
    qtbot.addWidget(monitor)
    monitor.find.setText("JMN")
    monitor.find_next()
    assert monitor.view.current == 9
    monitor.go_to_label("end")
    assert monitor.view.current == 12
    assert [monitor.listing.rows[r].line for r in monitor.follow(0o2000)] == [4, 9]
    assert monitor.uses.count() == 2 and monitor.uses_title.text().startswith("Uses of PUMP (02000): 2 lines")
    monitor._use_chosen(monitor.uses.item(1))
    assert monitor.view.current == 8


# --- the remote monitor ---------------------------------------------------------------------------------


def remote_monitor(qtbot, runtime: Runtime) -> tuple[RemoteSource, ProgramMonitor]:
    assert runtime.modbus is not None
    source = RemoteSource("127.0.0.1", runtime.modbus.port, program=runtime.program, symbols=runtime.symbols,
                          poll=0.05)
    monitor = ProgramMonitor(source, lambda: "eng1")
    qtbot.addWidget(monitor)
    return source, monitor


def test_the_remote_monitor_watches_a_running_station_over_modbus(qtbot, runtime: Runtime) -> None:
    engine = runtime.engine
    assert engine is not None
    source, monitor = remote_monitor(qtbot, runtime)
    try:
        engine.write_word(0o4000, 0x4242, user="test")
        engine.write_bit(0, 1, user="test")
        engine.write_bit(1, 1, user="test")
        wait(qtbot, lambda: (s := source.snapshot()) is not None and s.get_word(0o4002) == 0x4242
             and s.get_bit(0o2000) == 1)
        wait(qtbot, lambda: monitor.state.text().startswith("connected to tcp://127.0.0.1:"))
        monitor.add_watch("04400")
        monitor.add_watch("02001")
        engine.write_word(0o4400, 513, user="test")
        engine.write_bit(0o2001, 1, user="test")
        wait(qtbot, lambda: [monitor.watch.item(r, 1).text() for r in (0, 1)] == ["513", "1"])
        assert source.timer(0o3000) is None and source.counter(0o3010) is None  # not in the Modbus map
    finally:
        source.close()


def test_the_remote_monitor_is_read_only_and_says_so(qtbot, runtime: Runtime) -> None:
    """Modbus has no users: no control that would write, force, unforce or step is enabled, a line
    says the monitor is read-only, and the forces count says they are unknown over Modbus."""
    engine = runtime.engine
    assert engine is not None
    source, monitor = remote_monitor(qtbot, runtime)
    try:
        monitor.show()
        assert monitor.read_only.isVisible() and monitor.read_only.text().startswith("Read-only over Modbus")
        assert "Its forces are unknown here" in monitor.read_only.text()
        assert monitor.forced_pill.text() == "F: unknown over Modbus"
        assert READ_ONLY.startswith("read-only: Modbus has no users; ")
        for button in (monitor.step_button, monitor.unforce_button):
            assert not button.isEnabled() and button.toolTip() == READ_ONLY
        monitor.add_watch("04400")
        value = monitor.watch.item(0, 1)
        assert not value.flags() & Qt.ItemFlag.ItemIsEditable and value.toolTip() == READ_ONLY
        menu = QMenu(monitor)
        monitor._force_actions(menu, "word", 0o4400, "04400")
        assert [a.isEnabled() for a in menu.actions()] == [False, False, False]
        assert {a.toolTip() for a in menu.actions()} == {READ_ONLY}
        monitor.update_rights()  # a change of user changes nothing here
        assert not monitor.step_button.isEnabled() and not value.flags() & Qt.ItemFlag.ItemIsEditable
        value.setText("513")  # even a value put into the cell is not sent
        with pytest.raises(RuntimeError, match="read-only: Modbus has no users"):
            monitor.force("bit", 0, 1)
        assert runtime.commands is not None  # a force at the station: its value is seen, not the force
        assert runtime.commands.force(Who("eng1", Seat.CONSOLE), "bit", 0o2001, 1).result(5).ok
        wait(qtbot, lambda: (s := source.snapshot()) is not None and s.get_bit(0o2001) == 1)
        assert runtime.status().forced == 1 and monitor.forced_pill.text() == "F: unknown over Modbus"
        assert engine.snapshot.get_word(0o4400) == 0
        assert not [t for s, t in operator_texts(runtime) if s.startswith("modbus")]  # nothing was written
        window = ProgramWindow(source, lambda: "")
        qtbot.addWidget(window)
        assert window.windowTitle().endswith("(read-only)")
    finally:
        source.close()


def test_the_remote_monitor_says_what_it_is_doing(qtbot, tmp_path: Path) -> None:
    """`main.py monitor HOST:PORT`: no program to list, and a station that does not answer: the
    window says so (connecting, then the error) instead of showing a blank half-window."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # nothing listens there
    source = remote_source(f"127.0.0.1:{port}")
    window = ProgramWindow(source, lambda: "")
    qtbot.addWidget(window)
    try:
        window.resize(800, 500)
        window.show()
        monitor = window.monitor
        assert monitor.state.text().startswith(("connecting to tcp://127.0.0.1:", "link down: "))
        wait(qtbot, lambda: monitor.state.text().startswith("link down: cannot connect"))
        assert monitor.state.text().endswith("retrying every 0.2 s")
        image = monitor.view.viewport().grab().toImage()
        background = image.pixelColor(image.width() - 2, image.height() - 2)
        inked = sum(image.pixelColor(x, y) != background for x in range(0, 400, 2) for y in range(10, 40, 2))
        assert inked > 20  # the hint: no program to list, and what to give instead
    finally:
        window.close()  # closes the source


def test_the_monitor_command_target_is_a_station_or_host_port(qtbot, tmp_path: Path) -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    folder = station(tmp_path / "st", port)
    rt = Runtime(load_station(folder))
    rt.start()
    try:
        source = remote_source(str(folder))
        try:
            assert len(source.program.instrs) == 12 and source.symbols["PUMP"] == 0o2000
            wait(qtbot, lambda: source.snapshot() is not None)
            assert source.state().startswith("connected to tcp://127.0.0.1:")
        finally:
            source.close()
    finally:
        rt.stop()
    with pytest.raises(Problems, match=r"neither an opc\.tcp:// URL, a station folder nor HOST:PORT"):
        remote_source("no-such-thing")
    dead = remote_source(f"127.0.0.1:{port}")  # nothing listens there any more: said, not raised
    try:
        deadline = time.monotonic() + 5
        while not dead.error and time.monotonic() < deadline:
            QApplication.processEvents()
            time.sleep(0.02)
        assert dead.state().startswith("link down: cannot connect")
    finally:
        dead.close()


# --- the workstation ------------------------------------------------------------------------------------


def test_station_menu_opens_the_program_view_and_the_status_bar_counts_forces(qtbot, demo_copy: Path) -> None:
    from app.gui.main_window import MainWindow
    from app.gui.monitor.window import ProgramWindow

    cheap_demo_users(demo_copy)
    runtime = Runtime(load_station(demo_copy))
    runtime.start()
    window = MainWindow(runtime)
    qtbot.addWidget(window)
    try:
        menu = window.menuBar().actions()[0].menu()
        program = next(a for a in menu.actions() if a.text() == "&Program…")
        assert window.status.forced.text() == "F: 0 forced"
        program.trigger()  # the demo opens as a viewer: the view shows, its forcing is greyed
        opened = [w for w in window.viewers if isinstance(w, ProgramWindow)]
        assert len(opened) == 1 and opened[0].isVisible()
        monitor = opened[0].monitor
        assert len(monitor.listing) > 100
        for button in (monitor.step_button, monitor.unforce_button):
            assert not button.isEnabled() and "needs the engineer role; viewer is viewer" in button.toolTip()
        window.login("engineer", "engineer")  # the view follows who is at the workstation
        assert monitor.step_button.isEnabled() and monitor.unforce_button.isEnabled()
        monitor.force("bit", 0o2120, 1)
        wait(qtbot, lambda: runtime.status().forced == 1)
        window.refresh_status()
        assert window.status.forced.text() == "F: 1 forced"
        wait(qtbot, lambda: monitor.forced_pill.text() == "F: 1 forced")
    finally:
        window.close()
        runtime.stop()
    assert not opened[0].isVisible()


def test_main_monitor_command_refuses_a_bad_target_with_a_message(qtbot, capsys) -> None:
    """`main.py monitor nowhere`, as the command's own function in this process."""
    from app.cli import main

    assert main(["monitor", "nowhere"]) == 2
    err = capsys.readouterr().err
    assert "nowhere: neither an opc.tcp:// URL, a station folder nor HOST:PORT" in err
    assert "Traceback" not in err


def test_the_watch_table_forces_a_tag_in_physical_units(qtbot, tmp_path: Path) -> None:
    folder = station(tmp_path / "st")
    (folder / "tags.csv").write_text(
        "name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals\n"
        "TEMP_SP,LEVEL,word,°C,0,1000,0,200,1\nFLOW,04010,float32,m3/h,0,100,0,50,2\n", encoding="utf-8")
    toml = folder / "station.toml"
    toml.write_text('Tags = "tags.csv"\n' + toml.read_text(encoding="utf-8"), encoding="utf-8")
    rt = Runtime(load_station(folder))
    records: list[Record] = []
    rt.subscribe(records.append)
    rt.start()
    try:
        monitor = ProgramMonitor(LocalSource(rt), lambda: "eng1")
        qtbot.addWidget(monitor)
        engine = rt.engine
        assert engine is not None
        monitor.watch.item(0, 0).setText("TEMP_SP")
        monitor.watch.item(1, 0).setText("FLOW")
        assert [i.where for i in monitor.watch_items] == ["TEMP_SP", "FLOW"]
        monitor.force_tag(monitor.watch_items[0].tag, 130.0)  # type: ignore[arg-type]
        monitor.force_tag(monitor.watch_items[1].tag, None)  # bumpless: both words at 0.00
        wait(qtbot, lambda: monitor.forced_pill.text() == "F: 3 forced")
        wait(qtbot, lambda: monitor.watch.item(0, 4).text() == "F 130.0 °C (program view:eng1)")
        assert engine.snapshot.get_word(0o4000) == 650
        assert monitor.watch.item(0, 1).text() == "130.0 °C" and monitor.watch.item(0, 2).text() == "028Ah"
        assert monitor.watch.item(1, 4).text() == "F 0.00 m3/h (program view:eng1)"
        monitor.watch.item(0, 1).setText("10")  # an operator write loses to the force
        asked: list[str] = []
        monitor.ask = lambda title, text: asked.append(text) is None
        temp_sp = monitor.watch_items[0].tag
        assert temp_sp is not None
        with pytest.raises(ValueError, match=r"TEMP_SP is not forced: 1000\.0 °C is outside its range "
                                             r"0\.0 °C \.\. 200\.0 °C"):
            parse_force("1000", temp_sp)  # the tag's PhyMin..PhyMax, not the word's 0..13107 °C
        monitor.confirm_unforce_tag(monitor.watch_items[1].tag)  # type: ignore[arg-type]
        assert asked == ["Unforce FLOW? The memory keeps 0.00 m3/h, the forced value, until the program, "
                         "a node or an operator writes it."]
        wait(qtbot, lambda: monitor.forced_pill.text() == "F: 1 forced")
        monitor.watch.item(1, 1).setText("12,5")  # a write of both words, once unforced
        wait(qtbot, lambda: monitor.watch.item(1, 1).text() == "12.50 m3/h")
        assert engine.snapshot.get_word(0o4000) == 650
        texts = [(r.source, r.text) for r in records if r.kind == "operator"]
        assert ("program view:eng1", "force TEMP_SP: 0.0 -> 130.0 °C (raw 028Ah)") in texts
        assert ("program view:eng1", "force FLOW: 0.00 -> 0.00 m3/h (raw 0000h 0000h) (bumpless)") in texts
        assert ("program view:eng1", "unforce FLOW (was forced 0.00 m3/h)") in texts
        assert any(s == "program view:eng1" and t.startswith("write FLOW") and "12.50 m3/h" in t
                   for s, t in texts)  # one write of both words, in the tag's units
        monitor.watch.item(0, 1).setText("hot")
        assert "TEMP_SP" in monitor.message.text()
        monitor.grab()
    finally:
        rt.stop()


def test_a_station_serving_modbus_rtu_is_not_monitored_over_tcp(tmp_path: Path) -> None:
    write_station(tmp_path, 'NetPlcLoad = false\n[modbus_server]\ntransport = "rtu"\nport = "/dev/ttyUSB0"\n')
    with pytest.raises(Problems, match=r"modbus_server\.transport: the station serves Modbus RTU on "
                                       r"/dev/ttyUSB0, not TCP: monitor it over OPC UA"):
        remote_source(str(tmp_path))
