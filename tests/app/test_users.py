"""Users and roles, Qt-free: the users file, the session (who is at the workstation; what they may
do is the command layer's to say), and the `main.py users` command."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest

from app.authority import Action, Commands, Refusal, Source, Who
from app.authority.users import SCRYPT, Refused, Scrypt, Session, UserError, Users, UsersFileError
from app.cli import run_users
from app.station.config import DEMO_STATION
from netplc.engine import Engine
from netplc.program import parse
from netplc.records import ListSink
from tests.app.station_fork import Forks
from tests.cheap_users import CHEAP


def test_a_user_is_kept_as_a_salted_hash_never_the_password(tmp_path: Path) -> None:
    users = Users(tmp_path)
    users.add("ivan", "operator", "s3cret-Pa55", CHEAP)
    users.add("olga", "operator", "s3cret-Pa55", CHEAP)
    text = (tmp_path / "users.json").read_text(encoding="utf-8")
    assert "s3cret" not in text
    stored = {u["name"]: u for u in json.loads(text)["users"]}
    assert stored["ivan"]["salt"] != stored["olga"]["salt"]
    assert stored["ivan"]["hash"] != stored["olga"]["hash"]  # the same password, salted apart
    assert stored["ivan"]["scrypt"] == {"n": CHEAP.n, "r": CHEAP.r, "p": CHEAP.p}  # the cost beside it
    assert (tmp_path / "users.json").stat().st_mode & 0o077 == 0  # the owner's only
    again = Users(tmp_path)
    assert again.verify("ivan", "s3cret-Pa55") is not None
    assert again.verify("ivan", "wrong") is None and again.verify("nobody", "s3cret-Pa55") is None


def test_add_remove_and_passwd_say_what_is_wrong(tmp_path: Path) -> None:
    users = Users(tmp_path)
    users.add("ivan", "engineer", "a", CHEAP)
    with pytest.raises(UserError, match="exists already"):
        users.add("ivan", "operator", "b", CHEAP)
    with pytest.raises(UserError, match="role 'boss' is not one of viewer, operator, engineer, admin"):
        users.add("petr", "boss", "b", CHEAP)
    with pytest.raises(UserError, match="password is empty"):
        users.add("petr", "viewer", "", CHEAP)
    users.passwd("ivan", "new")  # hashed again at the default cost, the way to raise an old user's
    assert Users(tmp_path).get("ivan").scrypt == SCRYPT
    assert Users(tmp_path).verify("ivan", "a") is None
    assert Users(tmp_path).verify("ivan", "new").role == "engineer"
    users.remove("ivan")
    with pytest.raises(UserError, match="no user 'ivan'"):
        users.remove("ivan")
    (tmp_path / "users.json").write_text("{", encoding="utf-8")
    with pytest.raises(UserError, match=r"users\.json: not a users file"):
        Users(tmp_path)


@pytest.fixture
def users(tmp_path: Path) -> Users:
    users = Users(tmp_path)
    for role in ("viewer", "operator", "engineer", "admin"):
        users.add(role, role, role, CHEAP)
    return users


def layer(users: Users) -> Commands:
    """The command layer, reading the roles from these users as the runtime does."""
    def role_of(name: str) -> str | None:
        user = users.get(name)
        return None if user is None else user.role

    return Commands(Engine(parse("JMP 0\n")), ListSink(), role_of=role_of)


@pytest.mark.parametrize(("role", "allowed"), [
    ("viewer", set()), ("operator", {Action.WRITE, Action.ACKNOWLEDGE}),
    ("engineer", {Action.WRITE, Action.ACKNOWLEDGE, Action.FORCE, Action.STOP}),
    ("admin", {Action.WRITE, Action.ACKNOWLEDGE, Action.FORCE, Action.STOP, Action.USERS}),
])
def test_each_role_allows_what_the_ones_below_do(users: Users, role: str, allowed: set[Action]) -> None:
    session = Session(users)
    session.login(role, role)
    commands = layer(users)
    who = Who(session.name, Source.CONSOLE)
    for action in (Action.WRITE, Action.ACKNOWLEDGE, Action.FORCE, Action.STOP, Action.USERS):
        why = commands.denial(who, action)
        assert (why is None) == (action in allowed), action
        if why is not None:
            assert str(why).startswith(f"{action.value}: needs the ")
            assert str(why).endswith(f"; {role} is {role}")


def test_logged_out_is_the_default_viewer_or_nobody(users: Users) -> None:
    commands = layer(users)
    nobody = Session(users)
    assert nobody.name == ""
    assert commands.denial(Who(nobody.name, Source.CONSOLE), Action.WRITE, what="Пуск") == Refusal(
        "Пуск", "operator")
    default = Session(users, default="viewer")
    assert default.name == "viewer"
    # in parts, so the console says it in its own language (app/gui/words.py)
    assert commands.denial(Who(default.name, Source.CONSOLE), Action.WRITE, what="Пуск") == Refusal(
        "Пуск", "operator", "viewer", "viewer")
    with pytest.raises(Refused, match="wrong user name or password"):
        default.login("operator", "viewer")
    default.login("operator", "operator")
    default.logout()
    assert default.name == "viewer"
    assert not hasattr(default, "require") and not hasattr(default, "denial")  # the layer decides


def test_an_idle_user_is_logged_out(users: Users) -> None:
    now = [1000.0]
    session = Session(users, default="viewer", idle=60, clock=lambda: now[0])
    session.login("engineer", "engineer")
    now[0] += 59
    assert session.idle_expired() is None
    session.touch()
    now[0] += 59
    assert session.idle_expired() is None and session.name == "engineer"
    now[0] += 2
    assert session.idle_expired().name == "engineer"
    assert session.name == "viewer" and session.idle_expired() is None


def test_each_users_cost_is_kept_beside_its_hash_and_a_file_without_it_reads_at_the_default(
        tmp_path: Path) -> None:
    demo = Users(DEMO_STATION)  # written before the cost was kept: every user at the default
    assert {u.scrypt for u in demo.users.values()} == {SCRYPT} and demo.dearest == SCRYPT
    assert demo.verify("operator", "operator").role == "operator"
    users = Users(tmp_path)
    users.add("test", "viewer", "test", CHEAP)
    dearer = Scrypt(n=32, r=8, p=2)
    users.add("ivan", "operator", "ivan", dearer)  # as if the default had been raised since
    again = Users(tmp_path)
    assert again.get("test").scrypt == CHEAP and again.get("ivan").scrypt == dearer
    assert again.verify("test", "test") is not None and again.verify("ivan", "ivan") is not None
    assert again.verify("ivan", "test") is None
    assert again.dearest == dearer  # an unknown name costs what the dearest user costs
    assert Users(tmp_path / "nobody").dearest == SCRYPT  # no users: the default


@pytest.mark.parametrize("cost", [
    {"n": 3, "r": 8, "p": 1}, {"n": 2**30, "r": 8, "p": 1}, {"n": 16, "r": 0, "p": 1}, {"n": 16, "r": 8},
    {"n": "16", "r": 8, "p": 1}, {"n": True, "r": 8, "p": 1}, {"n": 2**16, "r": 1, "p": 1}, [16, 8, 1], None])
def test_a_cost_scrypt_cannot_use_is_named(tmp_path: Path, cost: object) -> None:
    entry = {"name": "ivan", "role": "viewer", "salt": "00ff", "hash": "abcd", "scrypt": cost}
    (tmp_path / "users.json").write_text(json.dumps({"users": [entry]}), encoding="utf-8")
    with pytest.raises(UsersFileError) as e:
        Users(tmp_path)
    assert e.value.problems == [
        f"{tmp_path / 'users.json'}: user 'ivan': scrypt must be "
        '{"n": a power of two from 2, "r": 1 or more, "p": 1 or more}, at most 128 MiB '
        "(set the password again: `main.py users passwd`)"]


def test_the_users_command(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                           capsys: pytest.CaptureFixture[str], station_forks: Forks) -> None:
    """The process once (its exit code, the default cost written; a fork of the worker's, as
    tests/app/station_fork.py starts `main.py`), the command's function for the rest (its exit
    code is main.py's)."""
    (tmp_path / "station.toml").write_text('NetPlcLoad = false\n', encoding="utf-8")
    (tmp_path / "password.txt").write_text("pw\n", encoding="utf-8")
    added = station_forks.start(["users", "--station", str(tmp_path), "add", "ivan", "--role", "engineer"],
                                tmp_path / "stderr.txt", stdin=tmp_path / "password.txt")
    assert added.wait(60) == 0, added.errors()
    assert json.loads((tmp_path / "users.json").read_text(encoding="utf-8"))["users"][0]["scrypt"] == {
        "n": 2**14, "r": 8, "p": 1}  # RFC 7914's interactive cost, whatever the tests use

    def users(*args: str, password: str = "") -> tuple[int, str, str]:
        monkeypatch.setattr("sys.stdin", io.StringIO(password + "\n"))
        code = run_users(["--station", str(tmp_path), *args])
        out, err = capsys.readouterr()
        return code, out, err

    code, _, err = users("add", "ivan", "--role", "viewer", password="pw")
    assert code == 1 and err == "users: user 'ivan' exists already (passwd changes the password)\n"
    code, out, _ = users("list")
    assert code == 0 and out.split() == ["ivan", "engineer"]
    assert users("passwd", "ivan", password="new")[0] == 0
    assert Users(tmp_path).verify("ivan", "new") is not None
    assert users("remove", "ivan")[0] == 0 and users("list")[1] == ""


def test_the_users_command_speaks_the_station_language(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "station.toml").write_text('NetPlcLoad = false\nLanguage = "ru"\n', encoding="utf-8")

    def users(*args: str) -> str:
        monkeypatch.setattr("sys.stdin", io.StringIO("pw\n"))
        assert run_users(["--station", str(tmp_path), *args]) == 0
        return capsys.readouterr().out

    assert users("add", "ivan", "--role", "engineer") == "пользователь ivan добавлен, роль engineer\n"
    assert users("passwd", "ivan") == "пароль пользователя ivan изменён\n"
    assert users("remove", "ivan") == "пользователь ivan удалён\n"
