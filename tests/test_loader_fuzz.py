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

import functools
import itertools
import json
import os
import random
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, example, given, settings
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

# numbers as text: small, past 64 bits, at the 64-bit limits, or of up to 6000 digits
NUMBER_TEXTS = (st.integers(-3, 70000).map(str), st.integers(-(2**70), 2**70).map(str),
                st.sampled_from([str(n) for n in (2**63, 2**64, -(2**63) - 1, 10**400)]),
                st.integers(1, 6000).map(lambda n: "9" * n))
PUNCTUATION = ["", " ", "\t", ",", ";", ":", "=", "$", "[", "]", ".", "#", "//", '"', "\\", "\x00", "\ufeff",
               "²", "Пуск", "\r", "\n"]
# a number or any text, alike: the four kinds of numbers and four times the text, one picked by
# `rows` for a field
MADE_WORDS = (*NUMBER_TEXTS, *[any_text(max_size=8)] * len(NUMBER_TEXTS))


@functools.cache
def exactly(n: int) -> st.SearchStrategy[bytes]:
    """`n` bytes: made once (hypothesis validates each new strategy)."""
    return st.binary(min_size=n, max_size=n)


def rows(fixed: list[str], made: tuple[st.SearchStrategy[str], ...], made_share: Fraction, most_rows: int,
         most_fields: int, sep: str) -> st.SearchStrategy[list[str]]:
    """Up to `most_rows` rows of up to `most_fields` fields joined by `sep`; a field is a value of one
    of `made` (each alike) at `made_share`, else one of `fixed`. Drawn as a byte a row (its number of
    fields), a byte a field (which, and of which of `made`), then each made value: a list of lists of
    `one_of`s took three draws a field and more, a list of `one_of`s of the made values two draws
    and two choices a value more than this, for the same texts (the draws were the tests' time)."""
    cut = round(256 * made_share)
    counts = st.binary(max_size=most_rows)

    def field(draw: st.DrawFn, b: int) -> str:
        if b < cut:
            return draw(made[b * len(made) // cut])
        return fixed[(b - cut) * len(fixed) // (256 - cut)]

    def draw_rows(draw: st.DrawFn) -> list[str]:
        sizes = [b % (most_fields + 1) for b in draw(counts)]
        fields = [field(draw, b) for b in draw(exactly(sum(sizes)))]
        ends = list(itertools.accumulate(sizes))
        return [sep.join(fields[end - size:end]) for size, end in zip(sizes, ends)]
    return st.composite(draw_rows)()


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The files the examples read beside the one they write: written once (no example changes them)."""
    folder = tmp_path_factory.mktemp("fuzz")
    (folder / "ok_symbols.csv").write_text("A,02000\nW,04000\n", encoding="utf-8")
    (folder / "x.png").write_bytes(b"not really a picture")
    (folder / "station").mkdir()
    (folder / "station" / "p.stl").write_text("JMP 0\n", encoding="utf-8")
    return folder


def encoded(text: str, how: str) -> bytes:
    if how == "cp1251":
        return text.encode("cp1251", errors="replace")
    if how == "bom":
        return text.encode("utf-8-sig")
    return text.encode("utf-8", errors="surrogatepass")


ENCODINGS = st.sampled_from(["utf-8", "bom", "cp1251"])
RAW = st.binary(max_size=300)


RAW_OR_TEXT = st.booleans()


def file_bytes(text: st.SearchStrategy[str]) -> st.SearchStrategy[bytes]:
    """What a file holds: any bytes or, as often, a text of `text` in one of ENCODINGS. Only what is
    written is drawn: a text and bytes drawn for every example, one thrown away, were half of the
    draws."""
    def draw_file(draw: st.DrawFn) -> bytes:
        if draw(RAW_OR_TEXT):
            return draw(RAW)
        return encoded(draw(text), draw(ENCODINGS))
    return st.composite(draw_file)()


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

PROGRAM_WORDS = [*LOGIC, "NODE", "NREAD", "MOV", "ADDBCD", "NSTORE", "C:", "N:", "S:", "D:", "R:", "L:",
                 "$02000", "$03770", "$04000", "$077777", "$7" * 3, "A", "A[3]", "A[" + "9" * 30 + "]",
                 "lbl:", "0.1", "A = $02000", "256", "-1", "0"]
# a token: a program word, punctuation, a number or any text, a quarter each
PROGRAM_LINES = rows([*PROGRAM_WORDS, *PUNCTUATION], MADE_WORDS, Fraction(1, 2), 12, 8, " ").map("\n".join)


@FUZZ
@given(data=file_bytes(PROGRAM_LINES), symbols=st.booleans())
@example(data=b"0.1 TNA $02000 ; a line number, a comment\n", symbols=False)  # reached now and then
def test_program_loads_or_names_its_errors(folder: Path, data: bytes, symbols: bool) -> None:
    path = folder / "p.stl"
    path.write_bytes(data)
    sym = folder / "ok_symbols.csv"
    loaded(path, lambda p: load_program(p, sym if symbols else None), ProgramError,
           lambda e: [str(d) for d in e.errors])


# --- symbols.csv and messages.csv --------------------------------------------------------------

CSV_WORDS = ["name", "A", "$02000", "04000", "8", "0", "1", "3", "text"]
LONG_FIELDS = st.integers(0, 200_000).map(lambda n: "x" * n if n > 131_000 else "x")
# a field: punctuation, CSV words, a number, any text or a field past the line's limit, a fifth each
CSV_TEXT = rows([*PUNCTUATION, *CSV_WORDS], (*MADE_WORDS, LONG_FIELDS), Fraction(3, 5), 8, 5,
                ",").map("\n".join)


@FUZZ
@given(data=file_bytes(CSV_TEXT), messages=st.booleans())
@example(data=b"1,1,9,a message of no type\n", messages=True)  # reached now and then
def test_symbols_and_messages_load_or_name_their_errors(folder: Path, data: bytes, messages: bool) -> None:
    path = folder / ("messages.csv" if messages else "symbols.csv")
    path.write_bytes(data)
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
TOML_WORDS = st.sampled_from(["true", "1e999", "nan", "-inf", "1.5", '""', '"p.stl"', '"/etc"', '"../x"',
                              '"a\\u0000b"', '[["02000", "02177"]]', '[["9", "1"]]', "[]", "{}",
                              '[{node = 0, endpoint = "tcp://127.0.0.1:1"}]',
                              '[{node = 300, endpoint = "x"}]', '[{node = 0, program = "p.stl"}]',
                              "[" * 2000 + "]" * 2000, '"Пуск"'])
# a number, a word of TOML or a string, a third each (in one one_of, one draw fewer than in two)
TOML_VALUES = st.one_of(*NUMBER_TEXTS, *[TOML_WORDS] * len(NUMBER_TEXTS),
                        *[any_text(max_size=10).map(json.dumps)] * len(NUMBER_TEXTS))
TOML_TEXT = st.lists(st.tuples(TOML_KEYS, TOML_VALUES).map(lambda kv: f"{kv[0]} = {kv[1]}"),
                     max_size=8).map("\n".join)


@FUZZ
@given(data=file_bytes(TOML_TEXT))
# a path out of the folder and writable ranges that parse: 200 examples reach them only now and then
@example(data=b'NetPlcProgram = "../x"\n'
              b'modbus_server.writable = [["02000", "02177"], ["04000", "02000"], "x"]')
def test_station_loads_or_names_its_errors(folder: Path, data: bytes) -> None:
    station = folder / "station"
    path = station / "station.toml"
    path.write_bytes(data)
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
ELEMENT_COUNT = st.integers(0, 3)


@st.composite
def form_documents(draw: st.DrawFn) -> Any:
    def props(names: st.SearchStrategy[list[str]]) -> dict[str, Any]:
        keys = draw(names)
        return {k: draw(PROPERTY_VALUES) for k in keys}

    elements = []
    for _ in range(draw(ELEMENT_COUNT)):
        el = {"type": draw(ELEMENT_TYPE), "Name": draw(ELEMENT_NAME), "x": 0, "y": 0, "w": 10, "h": 10}
        el.update(props(ELEMENT_KEYS))
        elements.append(el)
    doc: dict[str, Any] = {
        "form": {"width": 100, "height": 100, **props(FORM_KEYS)},
        "devices": draw(DEVICES),
        "images": draw(IMAGES),
        "elements": elements,
    }
    return doc


# a form's text: a document of form_documents or, half the time, any JSON (drawn only then); written
# as is, nested too deeply, with a number of 5000 digits, or any bytes instead
FORM_TEXT = st.one_of(form_documents(), JSON_VALUES).map(lambda doc: json.dumps(doc, ensure_ascii=False))
FORM_MODES = st.sampled_from(["json", "raw", "deep", "digits"])


@st.composite
def form_files(draw: st.DrawFn) -> bytes:
    """What a form's file holds, in one of FORM_MODES: only what is written is drawn (a text, its
    encoding and bytes drawn for every example, two thrown away, were a third of the draws)."""
    mode = draw(FORM_MODES)
    if mode == "raw":
        return draw(RAW)
    text = draw(FORM_TEXT)
    if mode == "deep":
        text = '{"elements": ' + "[" * 50_000 + "]" * 50_000 + ', "form": ' + text + "}"
    elif mode == "digits":
        text = text.replace("0", "1" * 5000, 1)
    return encoded(text, draw(ENCODINGS))


# an element that loads, past the form's edge: the examples build one only now and then (1 in 200)
BUILT = json.dumps({"form": {"width": 100, "height": 100}, "elements": [
    {"type": "StaticText", "Name": "t", "x": 0, "y": 0, "w": 200, "h": 10, "Text": "x"}]})


@FUZZ
@given(data=form_files())
@example(data=BUILT.encode())
def test_form_loads_or_names_its_errors(folder: Path, data: bytes) -> None:
    path = folder / "f.hmi"
    path.write_bytes(data)
    form = loaded(path, lambda p: load_form(p, {"A": 0o2000}), FormError, lambda e: e.problems)
    assert form is None or all(p.startswith(str(path)) for p in form.problems)


# --- tags.csv and users.json -------------------------------------------------------------------

TAG_WORDS = ["name", "address", "type", "unit", "h", "hh", "ll", "word", "bit", "float32", "int32", "04000",
             "040005", "A", "yes", "1e309", "nan", "-0", "Уровень", "°C"]
# a field: as in the CSV files, or a word of tags.csv: a sixth each
TAG_HEADER = "name,address,type,unit,app_min,app_max,phy_min,phy_max,h,hh,alarm_when"
TAG_TEXT = rows([*PUNCTUATION, *CSV_WORDS, *TAG_WORDS], (*MADE_WORDS, LONG_FIELDS), Fraction(1, 2),
                8, 8, ",").map(lambda lines: "\n".join([TAG_HEADER, *lines]))


@FUZZ
@given(data=file_bytes(TAG_TEXT))
def test_tags_load_or_name_their_errors(folder: Path, data: bytes) -> None:
    path = folder / "tags.csv"
    path.write_bytes(data)
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
@given(data=st.one_of(USER_DOCS.map(lambda doc: json.dumps(doc).encode()), RAW))
@example(data=b"\xff\xfe\x98")  # not text at all: 200 examples reach it only now and then
def test_users_load_or_name_their_errors(folder: Path, data: bytes) -> None:
    path = folder / USERS_FILE
    path.write_bytes(data)
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
