"""The remote Program view over a station's OPC UA endpoint (`main.py monitor opc.tcp://...`): logged
in as a user of that station, it reads NetPlc's memory and forces and acts only through the
station's methods and tag variables, which the station takes as commands of its layer with that
user. Against a real station (OPC UA on a free loopback port), a real asyncua client and the view
really rendered: what the user may not do is greyed as the station answers, and done anyway it is
refused by the station, journaled there once a minute naming the user."""

from __future__ import annotations

import io
import stat
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QDialog, QMenu

from app.authority import Source as Seat
from app.authority import Who
from app.cli import main
from app.gui.monitor.login import LoginDialog
from app.gui.monitor.source import RAW_WRITE, OpcUaSource
from app.gui.monitor.view import ProgramMonitor
from app.gui.monitor.window import ProgramWindow
from app.publish.client import Certificate, KnownStations, StationClient
from app.publish.pki import TrustList, thumbprint
from app.station.config import load_station
from app.station.runtime import Runtime
from netplc.records import Record
from tests.app.publish.conftest import free_port
from tests.app.test_monitor import station

TAGS = ("name,address,type,unit,app_min,app_max,phy_min,phy_max,decimals\n"
        "TEMP_SP,LEVEL,word,°C,0,1000,0,200,1\n")
DENIED = "the station answered BadUserAccessDenied"


class Station:
    """The monitor's test station (users eng1 engineer, olga operator, vera viewer) serving OPC UA."""

    def __init__(self, folder: Path, bound: str = "127.0.0.1") -> None:
        """`bound`: the address the endpoint is bound to (0.0.0.0: off loopback, secured)."""
        station(folder)
        (folder / "tags.csv").write_text(TAGS, encoding="utf-8")
        port = free_port()
        self.url = f"opc.tcp://127.0.0.1:{port}/netplc/"
        toml = folder / "station.toml"
        toml.write_text(f'Tags = "tags.csv"\n{toml.read_text(encoding="utf-8")}\n[opcua]\nenabled = true\n'
                        f'endpoint = "opc.tcp://{bound}:{port}/netplc/"\nwritable = ["TEMP_SP"]\n',
                        encoding="utf-8")
        self.folder = folder
        self.runtime = Runtime(load_station(folder))
        self.records: list[Record] = []
        self.runtime.subscribe(self.records.append)
        self.runtime.start()
        self.clients: list[StationClient] = []

    def client(self, user: str, config: Path) -> StationClient:
        client = StationClient(self.url, folder=config, period=0.05)
        self.clients.append(client)
        client.discover().result(10)
        client.open(user, user).result(20)
        return client

    def operator(self, who: str) -> list[str]:
        """The station's 'operator' records by the OPC UA session of `who`."""
        return [r.text or "" for r in self.records
                if r.kind == "operator" and (r.source or "").startswith(f"opcua:{who}@127.0.0.1:")]

    def close_clients(self) -> None:
        for client in self.clients:
            client.close()
        self.clients.clear()

    def stop(self) -> None:
        self.close_clients()
        self.runtime.stop()


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Station]:
    """One station for the module's tests: each logs in as a user of its own (the journal's records
    are told apart by user), and what one changes that another looks at is put back after it."""
    st = Station(tmp_path_factory.mktemp("monitor") / "st")
    try:
        yield st
    finally:
        st.stop()


@pytest.fixture
def remote(served: Station) -> Iterator[Station]:
    """The module's station for one test; after it, its clients logged out, no force left and
    NetPlc running."""
    yield served
    served.close_clients()
    commands, engineer = served.runtime.commands, Who("eng1", Seat.CONSOLE)
    assert commands is not None
    assert commands.unforce_all(engineer).result(10).ok
    if served.runtime.status().state != "running":
        assert served.runtime.run_program("eng1").result(10).ok


def monitor_of(qtbot, remote: Station, user: str, tmp_path: Path) -> ProgramMonitor:
    client = remote.client(user, tmp_path / "config")
    rt = remote.runtime
    source = OpcUaSource(client, program=rt.program, symbols=rt.symbols, tags=rt.tags.by_name)
    monitor = ProgramMonitor(source, lambda: client.user)
    qtbot.addWidget(monitor)
    return monitor


def wait(qtbot, what, timeout: int = 10000) -> None:
    qtbot.waitUntil(what, timeout=timeout)


def test_a_viewer_is_greyed_and_refused_by_the_station_once_a_minute_in_its_journal(
        qtbot, remote: Station, tmp_path: Path) -> None:
    monitor = monitor_of(qtbot, remote, "vera", tmp_path)
    monitor.show()
    assert not monitor.read_only.isVisible()  # over OPC UA the monitor acts, as far as the station lets it
    not_vera = "the station does not let vera do this"
    wait(qtbot, lambda: monitor.step_button.toolTip() == f"Step one scan: {not_vera}")
    assert not monitor.step_button.isEnabled() and not monitor.unforce_button.isEnabled()
    menu = QMenu(monitor)
    monitor._force_actions(menu, "bit", 0o2000, "02000")
    assert [a.isEnabled() for a in menu.actions()] == [False, False, False]
    assert menu.actions()[0].toolTip().endswith(not_vera)
    monitor.add_watch("TEMP_SP")
    monitor.add_watch("04400")  # an address: never written over OPC UA, there being no method for it
    wait(qtbot, lambda: "does not let vera" in monitor.watch.item(0, 1).toolTip())
    assert not monitor.watch.item(0, 1).flags() & Qt.ItemFlag.ItemIsEditable
    assert monitor.watch.item(1, 1).toolTip() == f"write 04400:word: {RAW_WRITE}"
    said: list[str] = []
    monitor.said.connect(said.append)
    for _ in range(3):  # done anyway: the station refuses, the view says why
        assert not monitor.force("bit", 0o2000, 1).result(10).ok
    assert not monitor.step().result(10).ok
    wait(qtbot, lambda: len(said) == 4)
    assert said[0].startswith(f"Refused: force 02000: {DENIED}") and said[-1].startswith(
        f"Refused: Step one scan: {DENIED}")
    assert monitor.message.text() == said[-1]
    assert remote.runtime.engine.forces.count == 0
    refused = [t for t in remote.operator("vera") if t.startswith("refused")]
    assert len(refused) == 2  # one per cause per minute: the force (3 refusals) and the step
    assert any(t.startswith("refused force bit 02000: needs the engineer role; vera is viewer")
               for t in refused)


def test_an_engineer_forces_steps_and_the_station_journals_the_engineer(
        qtbot, remote: Station, tmp_path: Path) -> None:
    monitor = monitor_of(qtbot, remote, "eng1", tmp_path)
    engine = remote.runtime.engine
    assert engine is not None
    wait(qtbot, lambda: monitor.step_button.isEnabled() and monitor.unforce_button.isEnabled())
    monitor.add_watch("PUMP")
    monitor.add_watch("TEMP_SP")
    wait(qtbot, lambda: bool(monitor.watch.item(1, 1).flags() & Qt.ItemFlag.ItemIsEditable))  # TEMP_SP
    assert monitor.force("bit", 0o2000, 1).result(10).ok  # answered once applied and journaled
    assert engine.forces.count == 1 and engine.snapshot.get_bit(0o2000) == 1
    wait(qtbot, lambda: monitor.forced_pill.text() == "F: 1 forced")
    wait(qtbot, lambda: monitor.watch.item(0, 4).text().startswith("F 1 (opcua:eng1@127.0.0.1:"))
    assert monitor.force_tag(monitor.watch_items[1].tag, 130.0).result(10).ok  # type: ignore[arg-type]
    wait(qtbot, lambda: monitor.watch.item(1, 1).text() == "130.0 °C")
    texts = remote.operator("eng1")
    assert "force 02000: 0 -> 1" in texts and "force TEMP_SP: 0.0 -> 130.0 °C (raw 028Ah)" in texts
    monitor.ask = lambda title, text: True  # the engineer confirms Unforce all
    monitor.unforce_button.click()
    wait(qtbot, lambda: monitor.forced_pill.text() == "F: 0 forced")
    assert engine.forces.count == 0
    assert not monitor.step().result(10).ok  # NetPlc runs: the station's layer refuses a step
    wait(qtbot, lambda: monitor.message.text().startswith(
        "Refused: Step one scan: the station answered BadInvalidArgument"))
    remote.runtime.stop_program("eng1").result(5)
    wait(qtbot, lambda: engine.snapshot.state.startswith("stopped"))
    before = engine.scan_counter
    assert monitor.step().result(10).ok
    assert engine.scan_counter > before
    assert any(t.startswith("step one scan") for t in remote.operator("eng1"))
    # a force made at the station's own workstation: the monitor sees it (not "unknown")
    assert remote.runtime.commands.force(Who("eng1", Seat.CONSOLE), "bit", 0o2001, 1).result(5).ok
    wait(qtbot, lambda: monitor.forced_pill.text() == "F: 1 forced")


def test_an_operator_writes_a_tag_and_may_not_force(qtbot, remote: Station, tmp_path: Path) -> None:
    monitor = monitor_of(qtbot, remote, "olga", tmp_path)
    engine = remote.runtime.engine
    assert engine is not None
    wait(qtbot, lambda: "does not let olga" in monitor.step_button.toolTip())
    assert not monitor.unforce_button.isEnabled()
    monitor.add_watch("TEMP_SP")
    wait(qtbot, lambda: bool(monitor.watch.item(0, 1).flags() & Qt.ItemFlag.ItemIsEditable))
    monitor.watch.item(0, 1).setText("42.4")  # a write of the tag's variable, in its units
    wait(qtbot, lambda: engine.snapshot.get_word(0o4000) == 212)
    wait(qtbot, lambda: any(t.startswith("write TEMP_SP") for t in remote.operator("olga")))
    assert any(t.startswith("write TEMP_SP") and "-> 42.4 °C" in t for t in remote.operator("olga")), \
        remote.operator("olga")
    assert not monitor.force("word", 0o4000, 7).result(10).ok
    assert not monitor.force_tag(monitor.watch_items[0].tag, None).result(10).ok  # type: ignore[arg-type]
    assert engine.forces.count == 0
    refused = [t for t in remote.operator("olga") if t.startswith("refused")]
    assert len(refused) == 1 and "needs the engineer role; olga is operator" in refused[0]


def test_the_login_dialog_says_a_refusal_and_logs_in(qtbot, remote: Station, tmp_path: Path) -> None:
    client = StationClient(remote.url, folder=tmp_path / "config", period=0.05)
    remote.clients.append(client)
    dialog = LoginDialog(client, "eng1")
    qtbot.addWidget(dialog)
    dialog.show()
    wait(qtbot, dialog.login.isEnabled)  # the station answered its discovery
    assert "loopback endpoint without security" in dialog.message.text()
    dialog.password.setText("wrong")
    dialog.login.click()
    wait(qtbot, lambda: "refused the login of 'eng1'" in dialog.message.text())
    assert dialog.login.isEnabled() and dialog.isVisible()
    dialog.password.setText("eng1")
    dialog.login.click()
    wait(qtbot, lambda: dialog.result() == QDialog.DialogCode.Accepted)
    assert client.snapshot is not None and client.user == "eng1"
    assert any((r.source or "").startswith("opcua eng1@127.0.0.1:")  # the failed login, journaled there
               and r.text == "refused log in: wrong user name or password" for r in remote.records)
    window = ProgramWindow(OpcUaSource(client), lambda: client.user)
    qtbot.addWidget(window)
    assert window.windowTitle().startswith("Program — eng1 at opc.tcp://127.0.0.1:")
    assert not window.windowTitle().endswith("(read-only)")
    window.monitor.step()  # NetPlc runs: refused, said in the status bar too
    wait(qtbot, lambda: window.statusBar().currentMessage().startswith(
        "Refused: Step one scan: the station answered BadInvalidArgument"))
    window.close()
    assert client._loop.loop is None  # closing the window logged out and stopped the client


def test_main_monitor_opcua_refuses_a_wrong_password_with_a_message(
        qtbot, remote: Station, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """`main.py monitor URL --user NAME`, its password the first line of stdin (not a terminal):
    run in this process, as the command's own function (tests/app/test_consoles.py runs `main.py
    console` as a process, for its exit status)."""
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))

    def monitor(*args: str, password: str) -> tuple[int, str]:
        monkeypatch.setattr(sys, "stdin", io.StringIO(password + "\n"))
        code = main(["monitor", *args])
        return code, capsys.readouterr().err

    code, err = monitor(remote.url, "--user", "eng1", password="wrong")
    assert code == 2 and "refused the login of 'eng1'" in err
    assert "Traceback" not in err
    dead = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    code, err = monitor(dead, "--user", "eng1", "--program", "nowhere.stl", password="eng1")
    assert code == 2 and "nowhere.stl: neither a program file nor a station folder" in err
    code, err = monitor(dead, "--user", "eng1", password="eng1")
    assert code == 2 and f"{dead}: no answer" in err and "Traceback" not in err


def test_off_loopback_the_monitor_trusts_the_station_once_and_an_admin_trusts_the_monitor(
        qtbot, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A station bound off loopback (0.0.0.0, reached on 127.0.0.1) serves Sign&Encrypt only: the
    monitor shows the station's certificate the first time and keeps it; the station refuses the
    monitor's own certificate until its admin trusts it; a station that changed its certificate
    since is refused before anything is sent."""
    remote = Station(tmp_path / "st", bound="0.0.0.0")
    config = tmp_path / "config"
    shown: list[Certificate] = []

    def login(trust: bool = True) -> LoginDialog:
        client = StationClient(remote.url, folder=config, period=0.05)
        remote.clients.append(client)
        monkeypatch.setattr(LoginDialog, "trust", lambda _self, cert: shown.append(cert) or trust)
        dialog = LoginDialog(client, "eng1", "eng1")  # a password given: it logs in by itself
        qtbot.addWidget(dialog)
        dialog.show()
        wait(qtbot, lambda: dialog.result() != 0 or dialog.isHidden(), 30000)
        return dialog

    try:
        dialog = login()  # first use: the station's certificate shown, trusted, kept
        station_der = (remote.folder / "pki" / "own" / "cert.der").read_bytes()
        assert [c.der for c in shown] == [station_der]
        assert shown[0].sha256 == Certificate(station_der).sha256 and len(shown[0].sha1) == 59
        assert KnownStations(config).verdict(remote.url, shown[0]) == "known"
        assert stat.S_IMODE((config / "known_stations.json").stat().st_mode) == 0o600
        assert stat.S_IMODE((config / "monitor" / "key.pem").stat().st_mode) == 0o600
        # ... but the station does not trust the monitor yet: said with the command that trusts it
        assert dialog.result() == QDialog.DialogCode.Rejected
        mine = thumbprint((config / "monitor" / "cert.der").read_bytes())
        assert f"python main.py opcua trust STATION {mine}" in dialog.error
        assert any(f"thumbprint {mine}" in (r.text or "") for r in remote.records)  # the station's journal
        TrustList(remote.folder).trust(mine)  # what `main.py opcua trust` does, by the station's admin
        dialog = login()  # known now: not asked again
        assert dialog.result() == QDialog.DialogCode.Accepted and len(shown) == 1
        source = OpcUaSource(dialog.client)
        assert source.force("bit", 0o2000, 1, "eng1").result(10).ok
        assert "force 02000: 0 -> 1" in remote.operator("eng1")
        # the station shows another certificate than the one trusted: refused, nothing sent
        known = config / "known_stations.json"
        known.write_text(known.read_text(encoding="utf-8").replace(shown[0].sha256[:5], "00:00"),
                         encoding="utf-8")
        dialog = login()
        assert dialog.result() == QDialog.DialogCode.Rejected and len(shown) == 1
        assert "shows another certificate than the one trusted before" in dialog.error
        assert dialog.client.snapshot is None
    finally:
        remote.stop()


def test_a_lost_link_is_said_and_the_monitor_logs_in_again(qtbot, remote: Station, tmp_path: Path) -> None:
    """Last of the module: it stops the station, and leaves it restarted."""
    monitor = monitor_of(qtbot, remote, "eng1", tmp_path)
    client = remote.clients[-1]
    wait(qtbot, lambda: monitor.state.text().startswith("eng1 at st: NetPlc running"))
    remote.runtime.stop()  # the station goes away
    wait(qtbot, lambda: monitor.state.text().startswith("link down: "))
    assert monitor.step_button.isEnabled()  # what the station said last still holds: it answers each action
    assert not monitor.force("bit", 0o2000, 1).result(10).ok  # not sent: said, not raised
    remote.runtime = Runtime(load_station(remote.folder))  # back, on the same endpoint
    remote.runtime.subscribe(remote.records.append)
    remote.runtime.start()
    wait(qtbot, lambda: monitor.state.text().startswith("eng1 at st: NetPlc running"), 30000)
    assert client.error == "" and monitor.force("bit", 0o2000, 1).result(10).ok
