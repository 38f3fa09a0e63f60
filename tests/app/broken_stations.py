"""Copies of the demo station, each broken in one way that once ended in a traceback, a hang, an
OOM or silence, with the problem `check` and the start must name instead.

tests/app/test_bad_files.py checks the words; tests/test_loader_fuzz.py runs them with random
corruptions of the demo's files and checks that none ends in anything but named problems.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from tests.app.conftest import DEMO_NAME


@dataclass(frozen=True)
class Broken:
    name: str
    plant: Callable[[Path], str]  # breaks the station folder; the problem expected (its start)
    refused: str = "load"  # where a start refuses: "load" (Runtime()), "start" (Runtime.start),
    # or "journal" (a form that does not load: the station runs, the problem journaled and shown)


def replace(path: Path, old: str, new: str) -> None:
    text = path.read_text(encoding="utf-8")
    assert old in text, (path, old)
    path.write_text(text.replace(old, new, 1), encoding="utf-8")


def append_line(path: Path, text: str) -> int:
    """Append lines; the number of the first."""
    old = path.read_text(encoding="utf-8")
    if not old.endswith("\n"):
        old += "\n"
    path.write_text(old + text + "\n", encoding="utf-8")
    return old.count("\n") + 1


def allow_outside(st: Path) -> None:
    replace(st / "station.toml", f'name = "{DEMO_NAME}"', f'name = "{DEMO_NAME}"\nallow_outside = true')


def link(path: Path, target: str | Path) -> None:
    path.unlink(missing_ok=True)
    os.symlink(target, path)


def replaced(path: Path, make: Callable[[Path], object]) -> Path:
    """`path`, its file replaced by what `make` makes there (a folder, a FIFO)."""
    path.unlink()
    make(path)
    return path


def users(st: Path, doc: object) -> Path:
    path = st / "users.json"
    path.write_text(doc if isinstance(doc, str) else json.dumps(doc), encoding="utf-8")
    return path


def _default_admin(st: Path) -> str:
    replace(st / "station.toml", 'default_user = "viewer"', 'default_user = "admin"')
    return f"{st / 'station.toml'}: operator.default_user: 'admin' is of role admin: the default user acts"


def _default_unknown(st: Path) -> str:
    replace(st / "station.toml", 'default_user = "viewer"', 'default_user = "nobody"')
    return f"{st / 'station.toml'}: operator.default_user: no user 'nobody' in {st / 'users.json'}"


def _users_not_json(st: Path) -> str:
    return f"{users(st, '{nope')}: not a users file: bad JSON at line 1, column 2"


def _users_shape(st: Path) -> str:
    return f'{users(st, {"users": {"viewer": 1}})}: not a users file: expected {{"users": [...]}}'


def _users_role(st: Path) -> str:
    path = users(st, {"users": [{"name": "viewer", "role": "king", "salt": "00", "hash": "00"}]})
    return f"{path}: user 'viewer': role 'king' is not one of viewer, operator, engineer, admin"


def _users_fields(st: Path) -> str:
    path = users(st, {"users": [{"name": "viewer", "role": "viewer"}]})
    return f"{path}: user 'viewer': salt, hash missing"


def _users_dev_zero(st: Path) -> str:
    link(st / "users.json", "/dev/zero")
    return f"{st / 'users.json'}: /dev/zero is outside the station folder {st}"


def _users_folder(st: Path) -> str:
    path = replaced(st / "users.json", Path.mkdir)
    return f"{path}: cannot read the users file: it is a folder, not a file"


def _program_loop(st: Path) -> str:
    link(st / "netplc.stl", "netplc.stl")
    return f"{st / 'station.toml'}: NetPlcProgram: {st / 'netplc.stl'}: a loop of symbolic links"


def _program_fifo(st: Path) -> str:
    program = replaced(st / "netplc.stl", os.mkfifo)
    return f"{st / 'station.toml'}: NetPlcProgram: file {program} is a FIFO (named pipe), not a file"


def _program_folder(st: Path) -> str:
    program = replaced(st / "netplc.stl", Path.mkdir)
    return f"{st / 'station.toml'}: NetPlcProgram: file {program} is a folder, not a file"


def _tags_dev_zero_allowed(st: Path) -> str:
    allow_outside(st)
    link(st / "tags.csv", "/dev/zero")
    return f"{st / 'station.toml'}: Tags: file /dev/zero is a character device, not a file"


def _tags_too_large(st: Path) -> str:
    with (st / "tags.csv").open("r+b") as f:
        f.truncate(17 * 1024 * 1024)  # sparse: costs no disk
    return f"{st / 'tags.csv'}:0: cannot read the tags: larger than 16 MB"


def _station_dev_zero(st: Path) -> str:
    link(st / "station.toml", "/dev/zero")
    return f"{st / 'station.toml'}: cannot read the station file: it is a character device, not a file"


def _symbols_400_digits(st: Path) -> str:
    line = append_line(st / "symbols.csv", "UNUSED,0" + "7" * 400)
    return f"{st / 'symbols.csv'}:{line}:8: an address of 401 characters names no memory"


def _symbols_no_memory(st: Path) -> str:
    line = append_line(st / "symbols.csv", "GAP,010000,between two data banks")
    return f"{st / 'symbols.csv'}:{line}:5: 010000 names no memory"


def _symbols_split(st: Path) -> str:
    line = append_line(st / "symbols.csv", '"SPL\nIT",02000')
    return f"{st / 'symbols.csv'}:{line}:1: a quoted field runs on to line {line + 1}: a row is one line"


def _form_dev_zero(st: Path) -> str:
    link(st / "forms" / "zz.hmi", "/dev/zero")
    return f"{st / 'forms' / 'zz.hmi'}: /dev/zero is outside the station folder {st}"


def _form_dev_zero_allowed(st: Path) -> str:
    allow_outside(st)
    link(st / "forms" / "zz.hmi", "/dev/zero")
    return f"{st / 'forms' / 'zz.hmi'}: cannot read the form: it is a character device, not a file"


def _form_folder(st: Path) -> str:
    (st / "forms" / "zz.hmi").mkdir()
    return f"{st / 'forms' / 'zz.hmi'}: cannot read the form: it is a folder, not a file"


def _image_loop(st: Path) -> str:
    form = st / "forms" / "02_analog.hmi"
    name = json.loads(form.read_text(encoding="utf-8"))["images"][0]
    link(form.parent / name, Path(name).name)
    return f'{form}: image #0: image file "{name}": a loop of symbolic links'


def _archive_folder(st: Path) -> str:
    archive = st / "archive" / "journal.sqlite"
    archive.mkdir(parents=True)
    return f"{st / 'station.toml'}: Archive: {archive}: cannot open the archive: it is a folder"


def _archive_not_sqlite(st: Path) -> str:
    archive = st / "archive" / "journal.sqlite"
    archive.parent.mkdir()
    archive.write_text("a journal written by something else\n" * 100, encoding="utf-8")
    return f"{st / 'station.toml'}: Archive: {archive}: cannot open the archive: not an SQLite database"


def _retain_folder(st: Path) -> str:
    retain = st / "archive" / "retain.bin"
    retain.mkdir(parents=True)
    return f"{st / 'station.toml'}: Retain: {retain} is a folder, not a file"


def _forces_dev_zero(st: Path) -> str:
    replace(st / "station.toml", f'name = "{DEMO_NAME}"', f'name = "{DEMO_NAME}"\nRetainForces = true')
    forces = st / "archive" / "retain.forces.json"
    forces.parent.mkdir()
    link(forces, "/dev/zero")
    return f"{st / 'station.toml'}: RetainForces: {forces} is a character device, not a file"


CASES = [
    Broken("default user admin", _default_admin),
    Broken("default user unknown", _default_unknown),
    Broken("users.json not JSON", _users_not_json),
    Broken("users.json wrong shape", _users_shape),
    Broken("users.json unknown role", _users_role),
    Broken("users.json missing fields", _users_fields),
    Broken("users.json is /dev/zero", _users_dev_zero),
    Broken("users.json is a folder", _users_folder),
    Broken("program links to itself", _program_loop),
    Broken("program is a FIFO", _program_fifo),
    Broken("program is a folder", _program_folder),
    Broken("tags.csv is /dev/zero (allow_outside)", _tags_dev_zero_allowed),
    Broken("tags.csv of 17 MB", _tags_too_large),
    Broken("station.toml is /dev/zero", _station_dev_zero),
    Broken("unused symbol of 400 digits", _symbols_400_digits),
    Broken("unused symbol naming no memory", _symbols_no_memory),
    Broken("symbol name over two lines", _symbols_split),
    Broken("form is /dev/zero", _form_dev_zero, "journal"),
    Broken("form is /dev/zero (allow_outside)", _form_dev_zero_allowed, "journal"),
    Broken("form is a folder", _form_folder, "journal"),
    Broken("form image links to itself", _image_loop, "journal"),
    Broken("Retain is a folder", _retain_folder),
    Broken("retained forces are /dev/zero", _forces_dev_zero),
    Broken("Archive is a folder", _archive_folder, "start"),
    Broken("Archive is not SQLite", _archive_not_sqlite, "start"),
]
