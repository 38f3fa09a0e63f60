"""Every loader of a station file, fed arbitrary input: a named error or success, never another exception.

The inputs are built from each format's own vocabulary (mnemonics, keys, addresses, property names)
mixed with arbitrary text, numbers past every limit, deep nesting and bytes that are not UTF-8, so
that the examples reach the checks behind the syntax. Example counts are bounded: a few seconds each.

Then whole station folders: copies of the demo with files damaged at random (seeded) through
`check` and the start, and the command line on the worst of the broken stations of
tests/app/broken_stations.py (whose words tests/app/test_bad_files.py checks), all in process: 0
tracebacks, and every problem names a file of the folder.
"""

from __future__ import annotations

import json
import os
import random
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from app import cli
from app.authority.policy import ROLES
from app.authority.users import USERS_FILE, Users, UsersFileError
from app.scada.table import read_tags
from app.station.check import check_station
from app.station.config import ConfigError, load_station, read_station
from app.station.runtime import Runtime, StartError
from hmi_forms.elements import ELEMENT_TYPES
from hmi_forms.form import FormError, load_form
from netplc.problems import Problems
from netplc.program import LOGIC, ProgramError, load_program, load_symbols
from registrar.catalog import Catalog, CatalogError
from tests.app.broken_stations import CASES
from tests.app.conftest import copy_demo
from tests.commands import run_in_process
from tests.unicode_text import any_text

FUZZ = settings(max_examples=200, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])

NUMBERS = st.one_of(st.integers(-3, 70000), st.integers(-(2**70), 2**70),
                    st.sampled_from([2**63, 2**64, -(2**63) - 1, 10**400]),
                    st.integers(1, 6000).map(lambda n: "9" * n))
NUMBER_TEXT = NUMBERS.map(str)
WORDS = st.one_of(
    st.sampled_from(["", " ", "\t", ",", ";", ":", "=", "$", "[", "]", ".", "#", "//", '"', "\\", "\x00",
                     "\ufeff", "²", "Пуск", "\r", "\n"]),
    NUMBER_TEXT,
    any_text(max_size=8),
)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


def encoded(text: str, how: str) -> bytes:
    if how == "cp1251":
        return text.encode("cp1251", errors="replace")
    if how == "bom":
        return text.encode("utf-8-sig")
    return text.encode("utf-8", errors="surrogatepass")


ENCODINGS = st.sampled_from(["utf-8", "bom", "cp1251"])
RAW = st.binary(max_size=300)


def loaded(path: Path, load: Callable[[Path], Any], error: type[Exception],
           problems: Callable[[Any], list[str]]) -> Any:
    """What `load(path)` returns, or None after checking that every problem it raised names the file."""
    try:
        return load(path)
    except error as e:
        found = problems(e)
        assert found and all(p.startswith(str(path)) for p in found), found
        return None

# --- program text ------------------------------------------------------------------------------

PROGRAM_TOKENS = st.one_of(
    st.sampled_from([*LOGIC, "NODE", "NREAD", "MOV", "ADDBCD", "NSTORE", "C:", "N:", "S:", "D:", "R:", "L:",
                     "$02000", "$03770", "$04000", "$077777", "$7" * 3, "A", "A[3]", "A[" + "9" * 30 + "]",
                     "lbl:", "0.1", "A = $02000", "256", "-1", "0"]),
    WORDS,
)
PROGRAM_LINES = st.lists(st.lists(PROGRAM_TOKENS, max_size=8).map(" ".join), max_size=12).map("\n".join)


@FUZZ
@given(text=PROGRAM_LINES, how=ENCODINGS, raw=RAW, use_raw=st.booleans(), symbols=st.booleans())
def test_program_loads_or_names_its_errors(folder: Path, text: str, how: str, raw: bytes, use_raw: bool,
                                           symbols: bool) -> None:
    path = folder / "p.stl"
    path.write_bytes(raw if use_raw else encoded(text, how))
    sym = folder / "ok_symbols.csv"
    sym.write_text("A,02000\nW,04000\n", encoding="utf-8")
    loaded(path, lambda p: load_program(p, sym if symbols else None), ProgramError,
           lambda e: [str(d) for d in e.errors])


# --- symbols.csv and messages.csv --------------------------------------------------------------

CSV_FIELDS = st.one_of(WORDS, st.sampled_from(["name", "A", "$02000", "04000", "8", "0", "1", "3", "text"]),
                       st.integers(0, 200_000).map(lambda n: "x" * n if n > 131_000 else "x"))
CSV_TEXT = st.lists(st.lists(CSV_FIELDS, max_size=5).map(",".join), max_size=8).map("\n".join)


@FUZZ
@given(text=CSV_TEXT, how=ENCODINGS, raw=RAW, use_raw=st.booleans(), messages=st.booleans())
def test_symbols_and_messages_load_or_name_their_errors(folder: Path, text: str, how: str, raw: bytes,
                                                        use_raw: bool, messages: bool) -> None:
    path = folder / ("messages.csv" if messages else "symbols.csv")
    path.write_bytes(raw if use_raw else encoded(text, how))
    if not messages:
        loaded(path, load_symbols, ProgramError, lambda e: [str(d) for d in e.errors])
    elif catalog := loaded(path, Catalog.load, CatalogError, lambda e: e.problems):
        assert all(0 <= m.number < 2**63 and 0 <= m.grp < 2**63 for m in catalog)


# --- station.toml ------------------------------------------------------------------------------

TOML_KEYS = st.sampled_from([
    "name", "NetPlcLoad", "NetPlcProgram", "Symbols", "HMIload", "NetSyncTime", "Archive", "Messages",
    "keep_days", "Retain", "modbus_server.port", "modbus_server.writable", "modbus_server.host",
    "modbus_server.unit", "modbus_server.enabled", "nodes", "simulators", "operator.users", "unknown",
])
TOML_VALUES = st.one_of(
    NUMBER_TEXT, st.sampled_from(["true", "1e999", "nan", "-inf", "1.5", '""', '"p.stl"', '"/etc"', '"../x"',
                                  '"a\\u0000b"', '[["02000", "02177"]]', '[["9", "1"]]', "[]", "{}",
                                  '[{node = 0, endpoint = "tcp://127.0.0.1:1"}]',
                                  '[{node = 300, endpoint = "x"}]', '[{node = 0, program = "p.stl"}]',
                                  "[" * 2000 + "]" * 2000, '"Пуск"']),
    any_text(max_size=10).map(json.dumps),
)
TOML_TEXT = st.lists(st.tuples(TOML_KEYS, TOML_VALUES).map(lambda kv: f"{kv[0]} = {kv[1]}"),
                     max_size=8).map("\n".join)


@FUZZ
@given(text=TOML_TEXT, how=ENCODINGS, raw=RAW, use_raw=st.booleans())
def test_station_loads_or_names_its_errors(folder: Path, text: str, how: str, raw: bytes,
                                           use_raw: bool) -> None:
    station = folder / "station"
    station.mkdir(exist_ok=True)
    (station / "p.stl").write_text("JMP 0\n", encoding="utf-8")
    path = station / "station.toml"
    path.write_bytes(raw if use_raw else encoded(text, how))
    _, problems = read_station(station)
    assert all(p.startswith(str(path)) for p in problems)
    assert loaded(station, load_station, ConfigError, lambda e: e.problems) or problems


# --- .hmi forms --------------------------------------------------------------------------------

JSON_LEAVES = st.one_of(
    st.none(), st.booleans(), st.integers(-(2**70), 2**70), st.floats(allow_nan=True), any_text(max_size=10),
    st.sampled_from(["02000", "04010", "A", "A.3", "#ff0000", "x.png", "/etc/passwd", "../../x.png",
                     "MiddleCenter"]))
JSON_VALUES = st.recursive(JSON_LEAVES, lambda inner: st.one_of(
    st.lists(inner, max_size=3), st.dictionaries(any_text(max_size=6), inner, max_size=3)), max_leaves=8)
# a property's value: a leaf, or a list or object of leaves, lists and objects (what a property
# holds, a list of states or points, is at most that deep); whole documents take JSON_VALUES
KEYS = any_text(max_size=6)
FLAT = st.one_of(st.lists(JSON_LEAVES, max_size=3), st.dictionaries(KEYS, JSON_LEAVES, max_size=3))
PROPERTY_VALUES = st.one_of(JSON_LEAVES, st.lists(st.one_of(JSON_LEAVES, FLAT), max_size=3),
                            st.dictionaries(KEYS, st.one_of(JSON_LEAVES, FLAT), max_size=3))
PROPERTY_NAMES = sorted({f for cls in ELEMENT_TYPES.values() for f in cls.__dataclass_fields__} |
                        {"type", "Address", "Image", "Device"})


# the strategies drawn from, made once: hypothesis validates each new one (more time than the draws)
ELEMENT_KEYS = st.lists(st.sampled_from(PROPERTY_NAMES), max_size=8)
FORM_KEYS = st.lists(st.sampled_from(["title", "width", "height", "BackColor", "Font", "BackgroundImage",
                                      "Nope"]), max_size=8)
ELEMENT_TYPE, ELEMENT_NAME = st.sampled_from([*ELEMENT_TYPES, "Nope"]), any_text(max_size=4)
DEVICES = st.lists(st.fixed_dictionaries({}, optional={
    k: PROPERTY_VALUES for k in ("Name", "AppMin", "AppMax", "PhyMin", "PhyMax")}), max_size=2)
IMAGES = st.lists(JSON_LEAVES, max_size=3)


@st.composite
def form_documents(draw: st.DrawFn) -> Any:
    def props(names: st.SearchStrategy[list[str]]) -> dict[str, Any]:
        keys = draw(names)
        return {k: draw(PROPERTY_VALUES) for k in keys}

    elements = []
    for _ in range(draw(st.integers(0, 3))):
        el = {"type": draw(ELEMENT_TYPE), "Name": draw(ELEMENT_NAME), "x": 0, "y": 0, "w": 10, "h": 10}
        el.update(props(ELEMENT_KEYS))
        elements.append(el)
    doc: dict[str, Any] = {
        "form": {"width": 100, "height": 100, **props(FORM_KEYS)},
        "devices": draw(DEVICES),
        "images": draw(IMAGES),
        "elements": elements,
    }
    return draw(st.one_of(st.just(doc), JSON_VALUES))


@FUZZ
@given(doc=form_documents(), how=ENCODINGS, raw=RAW, mode=st.sampled_from(["json", "raw", "deep", "digits"]))
def test_form_loads_or_names_its_errors(folder: Path, doc: Any, how: str, raw: bytes, mode: str) -> None:
    path = folder / "f.hmi"
    (folder / "x.png").write_bytes(b"not really a picture")
    text = json.dumps(doc, ensure_ascii=False)
    if mode == "deep":
        text = '{"elements": ' + "[" * 50_000 + "]" * 50_000 + ', "form": ' + text + "}"
    elif mode == "digits":
        text = text.replace("0", "1" * 5000, 1)
    path.write_bytes(raw if mode == "raw" else encoded(text, how))
    form = loaded(path, lambda p: load_form(p, {"A": 0o2000}), FormError, lambda e: e.problems)
    assert form is None or all(p.startswith(str(path)) for p in form.problems)


# --- tags.csv and users.json -------------------------------------------------------------------

TAG_FIELDS = st.one_of(CSV_FIELDS, st.sampled_from([
    "name", "address", "type", "unit", "h", "hh", "ll", "word", "bit", "float32", "int32", "04000", "040005",
    "A", "yes", "1e309", "nan", "-0", "Уровень", "°C"]))
TAG_TEXT = st.lists(st.lists(TAG_FIELDS, max_size=8).map(",".join), max_size=8).map(
    lambda rows: "\n".join(["name,address,type,unit,app_min,app_max,phy_min,phy_max,h,hh,alarm_when", *rows]))


@FUZZ
@given(text=TAG_TEXT, how=ENCODINGS, raw=RAW, use_raw=st.booleans())
def test_tags_load_or_name_their_errors(folder: Path, text: str, how: str, raw: bytes, use_raw: bool) -> None:
    path = folder / "tags.csv"
    path.write_bytes(raw if use_raw else encoded(text, how))
    table, problems = read_tags(path, {"A": 0o4000})
    assert all(p.startswith(f"{path}:") for p in problems), problems
    assert len({t.name for t in table.tags}) == len(table.tags)


USER_ENTRIES = st.one_of(JSON_VALUES, st.fixed_dictionaries({}, optional={
    "name": st.one_of(any_text(max_size=5), JSON_LEAVES),
    "role": st.one_of(st.sampled_from(ROLES), JSON_LEAVES),
    "salt": st.one_of(st.just("00ff"), JSON_LEAVES),
    "hash": st.one_of(st.just("abcd"), JSON_LEAVES)}))
USER_DOCS = st.one_of(JSON_VALUES, st.fixed_dictionaries({"users": st.lists(USER_ENTRIES, max_size=4)}))


@FUZZ
@given(doc=USER_DOCS, raw=RAW, use_raw=st.booleans())
def test_users_load_or_name_their_errors(folder: Path, doc: Any, raw: bytes, use_raw: bool) -> None:
    path = folder / USERS_FILE
    path.write_bytes(raw if use_raw else json.dumps(doc).encode())
    users = loaded(folder, Users, UsersFileError, lambda e: e.problems)
    for user in users.users.values() if users is not None else ():
        assert user.role in ROLES and bytes.fromhex(user.salt) and bytes.fromhex(user.hash)


# --- whole station folders: check and the start -------------------------------------------------

STATION_FILES = ["station.toml", "netplc.stl", "symbols.csv", "messages.csv", "tags.csv", "users.json",
                 "node0.stl", "forms/01_trigger.hmi", "forms/02_analog.hmi", "forms/03_sync.hmi"]
PIECES = [b'"', b"\n", b"\x00", b"\x98", b"\xff\xfe", b"9" * 400, b"[" * 50, "Пуск".encode("cp1251"), b"$",
          b",,,", b"=", b"\r", b"\\", b"{}", b"0" + b"7" * 30, b"-", b"#", b"'", b"null", b"1e999"]


def corrupt(data: bytes, rng: random.Random) -> bytes:
    """`data` damaged the ways files get damaged: a byte changed, cut short, text pasted in, a line
    lost or doubled."""
    lines = data.split(b"\n")
    at = rng.randrange(len(data) + 1)
    how = rng.randrange(6)
    if how == 0:
        spots = [rng.randrange(len(data)) for _ in range(rng.randint(1, 5))] if data else []
        out = bytearray(data)
        for spot in spots:
            out[spot] = rng.randrange(256)
        return bytes(out)
    if how == 1:
        return data[:at]
    if how == 2:
        return data[:at] + rng.choice(PIECES) + data[at:]
    i = rng.randrange(len(lines))
    if how == 3:
        del lines[i]
    elif how == 4:
        lines.insert(i, lines[i])
    else:
        j = rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    return b"\n".join(lines)


def named(problems: list[str], station: Path) -> None:
    """Problems there are, and each names a file of the station folder."""
    assert problems and all(p.startswith(f"{station}{os.sep}") for p in problems), problems


def checked_and_started(station: Path, start: bool) -> None:
    """`check` and the start end in a report or in named problems, never in another exception."""
    report = check_station(station)
    if not report.ok:
        named(report.problems, station)
    try:
        runtime = Runtime(load_station(station))
    except Problems as e:
        named(e.problems, station)
        assert not report.ok  # what a start refuses, check reports
        return
    if not start:
        return
    try:
        runtime.start()
    except StartError as e:
        named(e.problems, station)
    finally:
        runtime.stop()


def test_damaged_demo_stations_end_in_named_problems_or_run(tmp_path: Path) -> None:
    """30 copies of the demo, 1-3 files of each damaged (seeded). A start only where station.toml is
    intact (a damaged host name could wait on a name server), and at most 3: a start costs 0.2 s."""
    starts = 3
    for seed in range(30):
        rng = random.Random(seed)
        station = copy_demo(tmp_path / str(seed))
        damaged = rng.sample(STATION_FILES, rng.randint(1, 3))
        for name in damaged:
            path = station / name
            path.write_bytes(corrupt(path.read_bytes(), rng))
        start = starts > 0 and "station.toml" not in damaged
        starts -= start
        try:
            checked_and_started(station, start)
        except BaseException as e:
            e.add_note(f"seed {seed}: {', '.join(damaged)} damaged")
            raise


def test_main_check_and_the_headless_start_print_named_problems_not_tracebacks(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The command line on the two cases that ended in tracebacks (RuntimeError for a program that is
    a link to itself, MemoryError for a form that is a link to /dev/zero), in this process
    (tests/commands.py; an exception would end the test, and the log's tracebacks are in stderr):
    tests/app/test_bad_files.py runs `check` and a start as processes of their own."""
    loop, zero = (next(c for c in CASES if c.name == name) for name in ("program links to itself",
                                                                       "form is /dev/zero"))
    station = copy_demo(tmp_path / "check", "en")  # the cases' problems are English
    expected = loop.plant(station)
    check = run_in_process(cli.main, ["check", station], capsys)
    assert check.returncode == 1 and "Traceback" not in check.stderr, check.stdout + check.stderr
    assert check.stdout.startswith(expected), check.stdout
    station = copy_demo(tmp_path / "start", "en")
    shown = zero.plant(station)
    start = run_in_process(cli.main, ["--no-gui", station, "--duration", "0.5", "--status-every", "0.2"],
                           capsys)
    assert start.returncode == 0 and "Traceback" not in start.stderr, start.stderr  # runs without the form
    assert f"form problem: {shown}" in start.stdout, start.stdout
