"""Users and roles, Qt-free: the users file, the session (who is at the workstation; what they may
do is the command layer's to say), and the `main.py users` command."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from app.authority import Action, Commands, Refusal, Source, Who
from app.authority.users import Refused, Session, UserError, Users
from netplc.engine import Engine
from netplc.program import parse
from netplc.records import ListSink

REPO = Path(__file__).resolve().parents[2]


def test_a_user_is_kept_as_a_salted_hash_never_the_password(tmp_path: Path) -> None:
    users = Users(tmp_path)
    users.add("ivan", "operator", "s3cret-Pa55")
    users.add("olga", "operator", "s3cret-Pa55")
    text = (tmp_path / "users.json").read_text(encoding="utf-8")
    assert "s3cret" not in text
    stored = {u["name"]: u for u in json.loads(text)["users"]}
    assert stored["ivan"]["salt"] != stored["olga"]["salt"]
    assert stored["ivan"]["hash"] != stored["olga"]["hash"]  # the same password, salted apart
    assert (tmp_path / "users.json").stat().st_mode & 0o077 == 0  # the owner's only
    again = Users(tmp_path)
    assert again.verify("ivan", "s3cret-Pa55") is not None
    assert again.verify("ivan", "wrong") is None and again.verify("nobody", "s3cret-Pa55") is None


def test_add_remove_and_passwd_say_what_is_wrong(tmp_path: Path) -> None:
    users = Users(tmp_path)
    users.add("ivan", "engineer", "a")
    with pytest.raises(UserError, match="exists already"):
        users.add("ivan", "operator", "b")
    with pytest.raises(UserError, match="role 'boss' is not one of viewer, operator, engineer, admin"):
        users.add("petr", "boss", "b")
    with pytest.raises(UserError, match="password is empty"):
        users.add("petr", "viewer", "")
    users.passwd("ivan", "new")
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
        users.add(role, role, role)
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


def test_the_users_command(tmp_path: Path) -> None:
    (tmp_path / "station.toml").write_text('NetPlcLoad = false\n', encoding="utf-8")

    def users(*args: str, password: str = "") -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "main.py", "users", "--station", str(tmp_path), *args],
                              input=password + "\n", cwd=REPO, capture_output=True, text=True, timeout=60)

    assert users("add", "ivan", "--role", "engineer", password="pw").returncode == 0
    listed = users("list")
    assert listed.returncode == 0 and listed.stdout.split() == ["ivan", "engineer"]
    again = users("add", "ivan", "--role", "viewer", password="pw")
    assert again.returncode == 1 and "users: user 'ivan' exists already" in again.stderr
    assert "Traceback" not in again.stderr
    assert users("passwd", "ivan", password="new").returncode == 0
    assert Users(tmp_path).verify("ivan", "new") is not None
    assert users("remove", "ivan").returncode == 0 and users("list").stdout == ""


def test_the_users_command_speaks_the_station_language(tmp_path: Path) -> None:
    (tmp_path / "station.toml").write_text('NetPlcLoad = false\nLanguage = "ru"\n', encoding="utf-8")

    def users(*args: str) -> str:
        return subprocess.run([sys.executable, "main.py", "users", "--station", str(tmp_path), *args],
                              input="pw\n", cwd=REPO, capture_output=True, text=True, timeout=60).stdout

    assert users("add", "ivan", "--role", "engineer") == "пользователь ivan добавлен, роль engineer\n"
    assert users("passwd", "ivan") == "пароль пользователя ivan изменён\n"
    assert users("remove", "ivan") == "пользователь ivan удалён\n"
