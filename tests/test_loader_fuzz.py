"""Every loader of a station file, fed arbitrary input: a named error or success, never another exception.

The inputs are built from each format's own vocabulary (mnemonics, keys, addresses, property names)
mixed with arbitrary text, numbers past every limit, deep nesting and bytes that are not UTF-8, so
that the examples reach the checks behind the syntax. Example counts are bounded: a few seconds each.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from app.config import ConfigError, load_station, read_station
from hmi_forms.elements import ELEMENT_TYPES
from hmi_forms.form import FormError, load_form
from netplc.program import LOGIC, ProgramError, load_program, load_symbols
from registrar.catalog import Catalog, CatalogError

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
    st.text(max_size=8),
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
    st.text(max_size=10).map(json.dumps),
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
    st.none(), st.booleans(), st.integers(-(2**70), 2**70), st.floats(allow_nan=True), st.text(max_size=10),
    st.sampled_from(["02000", "04010", "A", "A.3", "#ff0000", "x.png", "/etc/passwd", "../../x.png",
                     "MiddleCenter"]))
JSON_VALUES = st.recursive(JSON_LEAVES, lambda inner: st.one_of(
    st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=6), inner, max_size=3)), max_leaves=8)
PROPERTY_NAMES = sorted({f for cls in ELEMENT_TYPES.values() for f in cls.__dataclass_fields__} |
                        {"type", "Address", "Image", "Device"})


@st.composite
def form_documents(draw: st.DrawFn) -> Any:
    def props(names: list[str]) -> dict[str, Any]:
        keys = draw(st.lists(st.sampled_from(names), max_size=8))
        return {k: draw(JSON_VALUES) for k in keys}

    elements = []
    for _ in range(draw(st.integers(0, 3))):
        el = {"type": draw(st.sampled_from([*ELEMENT_TYPES, "Nope"])), "Name": draw(st.text(max_size=4)),
              "x": 0, "y": 0, "w": 10, "h": 10}
        el.update(props(PROPERTY_NAMES))
        elements.append(el)
    doc: dict[str, Any] = {
        "form": {"width": 100, "height": 100, **props(["title", "width", "height", "BackColor", "Font",
                                                       "BackgroundImage", "Nope"])},
        "devices": draw(st.lists(st.fixed_dictionaries({}, optional={
            k: JSON_VALUES for k in ("Name", "AppMin", "AppMax", "PhyMin", "PhyMax")}), max_size=2)),
        "images": draw(st.lists(JSON_LEAVES, max_size=3)),
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
