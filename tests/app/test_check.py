"""`python main.py check`: every error planted in a broken copy of the demo station is reported. The
checks run in this process (`app.cli.main`, what main.py runs, tests/commands.py): the demo's check
as a process of its own is tests/test_package.py's (the installed command, exit code 0), a check
that exits 1 tests/app/test_bad_files.py's."""

from __future__ import annotations

import csv
import json
import re
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

from app.cli import main
from tests.app.conftest import DEMO, copy_demo
from tests.commands import run_in_process


@pytest.fixture
def run_check(capsys: pytest.CaptureFixture[str]) -> Callable[[Path], subprocess.CompletedProcess[str]]:
    """`python main.py check STATION`, in this process."""
    return lambda station: run_in_process(main, ["check", station], capsys)


def test_the_demo_station_is_clean(run_check) -> None:
    r = run_check(DEMO)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "норма: программа netplc.stl: инструкций" in r.stdout  # the demo's Language is ru


def plant(path: Path, old: str, new: str) -> None:
    text = path.read_text(encoding="utf-8")
    assert old in text, (path, old)
    path.write_text(text.replace(old, new, 1), encoding="utf-8")


def test_every_planted_error_is_found(tmp_path: Path, run_check) -> None:
    st = copy_demo(tmp_path / "broken")
    plant(st / "station.toml", "NetSyncTime = 100", 'NetSyncTime = "fast"\nColour = "red"')
    plant(st / "station.toml", "timeout = 0.5", 'timeout = 0.5\nendpoint = "tcp://plc:99999"')
    plant(st / "netplc.stl", "TNA ON\nFON C:$02140 N:NODE S:0", "TNX ON\nFON C:$02140 N:NODE S:0")
    plant(st / "netplc.stl", "FON C:NRD N:NREAD S:4000 D:TRIG_IN R:2",
          "FON C:NRD N:NREAD S:4000 D:NO_SUCH R:2")
    plant(st / "netplc.stl", "TNA ON\nFON C:$02134 N:NWRITE", "TNA ON\nFON C:$02500 N:NODE S:7\n"
          "TNA ON\nFON C:$02134 N:NWRITE")
    plant(st / "symbols.csv", "PUMP,02120", "PUMP,02190")
    plant(st / "node0.stl", "CTR TB N:2", "CTR TB N:999")
    plant(st / "messages.csv", "3,1,2,", "3,1,alarm,")
    forms = sorted((st / "forms").glob("*.hmi"))
    form = json.loads(forms[0].read_text(encoding="utf-8")) if forms else {
        "form": {"title": "t", "width": 100, "height": 100}, "elements": []}
    form["elements"].append({"type": "DiscreteBase", "Name": "Broken", "x": 0, "y": 0, "w": 10, "h": 10,
                             "InAddr": "09999"})
    form["elements"].append({"type": "NoSuchElement", "Name": "Alien", "x": 0, "y": 0, "w": 10, "h": 10})
    (st / "forms" / "zz_broken.hmi").write_text(json.dumps(form, ensure_ascii=False), encoding="utf-8")

    r = run_check(st)
    assert r.returncode == 1
    out = r.stdout
    lines = (st / "netplc.stl").read_text(encoding="utf-8").splitlines()
    tnx = lines.index("TNX ON") + 1
    nosuch = next(i for i, line in enumerate(lines, 1) if "NO_SUCH" in line)
    node7 = lines.index("FON C:$02500 N:NODE S:7") + 1
    node_lines = (st / "node0.stl").read_text(encoding="utf-8").splitlines()
    ctr = node_lines.index("CTR TB N:999") + 1
    expected = [
        f"{st / 'station.toml'}: NetSyncTime: ожидается целое число, а задано 'fast'",  # the demo's ru
        f"{st / 'station.toml'}: Colour: неизвестный параметр",
        f"{st / 'station.toml'}: nodes[0].endpoint: endpoint 'tcp://plc:99999'",
        f"{st / 'netplc.stl'}:{tnx}:1: неизвестная инструкция 'TNX'",
        f"{st / 'netplc.stl'}:{nosuch}:",
        f"{st / 'netplc.stl'}:{node7}:1: NODE S:7: узел 7 не задан",  # found past other errors
        f"{st / 'symbols.csv'}:",
        f"{st / 'node0.stl'}:{ctr}:",
        "messages.csv:",
        'zz_broken.hmi: элемент "Broken": InAddr',
        'zz_broken.hmi: элемент "Alien"',
    ]
    for e in expected:
        assert e in out, f"{e!r} not in:\n{out}"
    assert f"найдено проблем: {len(out.splitlines())}" in r.stderr


def test_check_reports_exactly_what_a_start_refuses(tmp_path: Path) -> None:
    from app.station.check import check_station
    from app.station.config import load_station
    from app.station.runtime import Runtime, StartError

    st = copy_demo(tmp_path / "broken")
    plant(st / "netplc.stl", "TNA ON\nFON C:$02140 N:NODE S:0", "TNX ON\nFON C:$02140 N:NODE S:7")
    plant(st / "node0.stl", "CTR TB N:2", "CTR TB N:999")
    plant(st / "messages.csv", "3,1,2,", "3,1,alarm,")
    with pytest.raises(StartError) as refused:
        Runtime(load_station(st))
    assert len(refused.value.problems) == 4  # the bad line, NODE 7 further down, the node, the message
    assert check_station(st).problems == refused.value.problems


@pytest.mark.parametrize("language", ["en", "ru"])
def test_tags_csv_problems_are_reported_by_check(tmp_path: Path, language: str, run_check) -> None:
    """In the station's language, naming the file, the line, the tag and its values as they are."""
    st = copy_demo(tmp_path / "tags", language)
    plant(st / "tags.csv", "LEVEL,LEVEL,word,%,0,4095,0,100,1,Уровень,95,90,",
          "LEVEL,LEVEL,word,%,0,4095,0,100,1,Уровень,85,90,")
    plant(st / "tags.csv", "TEMP,TEMP,word,°C,0,1000,", "TEMP,TEMP,word,°C,7,7,")
    plant(st / "tags.csv", "TRIGGER,040005,bit,", "TRIGGER,010000,bit,")
    r = run_check(st)
    assert r.returncode == 1
    tags = st / "tags.csv"
    lines = tags.read_text(encoding="utf-8").splitlines()
    level = next(i for i, line in enumerate(lines, 1) if line.startswith("LEVEL,"))
    said = {
        "en": [f"{tags}:{level}: LEVEL: HH 85 is below H 90: the limits must keep the order",
               f"{tags}:{level + 1}: TEMP: app_min = app_max = 7: the conversion is undefined",
               f"{tags}:{level + 3}: TRIGGER: address '010000' cannot hold an I/O bit or a data bit"],
        "ru": [f"{tags}:{level}: LEVEL: HH 85 ниже H 90: пределы должны идти в порядке",
               f"{tags}:{level + 1}: TEMP: app_min = app_max = 7: преобразование не определено",
               f"{tags}:{level + 3}: TRIGGER: address '010000' не может вместить бит ввода-вывода"],
    }[language]
    for line in said:
        assert line in r.stdout, r.stdout
    if language != "en":
        return
    plant(st / "station.toml", 'Tags = "tags.csv"', 'Tags = "no_tags.csv"')
    r = run_check(st)
    assert f"{st / 'station.toml'}: Tags: file {st / 'no_tags.csv'} does not exist" in r.stdout


def test_a_horn_bit_the_program_writes_is_a_problem(tmp_path: Path) -> None:
    from app.station.check import check_station

    station = copy_demo(tmp_path / "st")
    toml = station / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8").replace('alarm_horn = "03600"', 'alarm_horn = "02200"'),
                    encoding="utf-8")
    problems = check_station(station).problems
    assert any("alarm_horn: бит 02200 пишет программа (строка " in p and "может только читать" in p
               for p in problems), problems


@pytest.mark.parametrize("language", ["ru", "en"])
def test_station_toml_problems_are_said_in_the_station_language(tmp_path: Path, language: str) -> None:
    """station.toml's reader says its problems in the file's `Language` (app/scada/words.py), each
    naming the file, the key and the value as they are; a Russian one leaves no English word of
    the catalogue."""
    from app.station.check import check_station

    st = copy_demo(tmp_path / "st", language)
    plant(st / "station.toml", "NetSyncTime = 100", 'NetSyncTime = "fast"\nColour = "red"\nkeep_days = -5')
    plant(st / "station.toml", "keep_days = 30 ", "")
    plant(st / "station.toml", 'Messages = "messages.csv"', 'Messages = ""')
    plant(st / "station.toml", 'Retain = "archive/retain.bin"', 'Retain = "../../elsewhere.bin"')
    plant(st / "station.toml", "[modbus_server]", '[modbus_server]\ntransport = "ascii"')
    toml = st / "station.toml"
    problems = [p.removeprefix(f"{toml}: ") for p in check_station(st).problems if p.startswith(f"{toml}: ")]
    said = {
        "ru": ["NetSyncTime: ожидается целое число, а задано 'fast'", "Colour: неизвестный параметр",
               "keep_days: -5 вне диапазона 0-", "Messages: пустой путь", "Retain: ",
               "modbus_server.transport: 'ascii' — не одно из: tcp, rtu"],
        "en": ["NetSyncTime: expected an integer, got 'fast'", "Colour: unknown setting",
               "keep_days: -5 is outside 0-", "Messages: empty path", "Retain: ",
               "modbus_server.transport: 'ascii' is not one of tcp, rtu"],
    }[language]
    for line in said:
        assert any(p.startswith(line) for p in problems), f"{line!r} not in {problems}"
    outside = "вне папки станции" if language == "ru" else "is outside the station folder"
    assert any(p.startswith("Retain: ") and outside in p for p in problems), problems
    if language == "ru":
        russian_leaves_no_english(problems)


def russian_leaves_no_english(problems: list[str]) -> None:
    """No English word of the catalogue in Russian problems, past file names, quoted values and
    names as they are."""
    from tests.app.scada.test_words import english_words

    prose = (re.sub(r"\S*[/.:]\S*|'[^']*'|\b[A-Za-z_]+ = \w+", "", p) for p in problems)
    left = {w for p in prose for w in re.findall(r"[A-Za-z]{2,}", p)} & english_words()
    assert not left, f"English words in Russian problems: {sorted(left)}: {problems}"


@pytest.mark.parametrize("language", ["ru", "en"])
def test_readers_problems_are_said_in_the_station_language(tmp_path: Path, language: str) -> None:
    """The program reader's diagnostics (instruction, operand, address, jump, a function's
    parameters), symbols.csv's, the forms', messages.csv's, users.json's and a node's settings',
    a file that is not text, a CSV line the csv module refuses and a form that is not JSON,
    naming file, line, column, element, property, user, key and the text as it is."""
    from app.station.check import check_station

    st = copy_demo(tmp_path / "st", language)
    stl = st / "netplc.stl"
    program = stl.read_text(encoding="utf-8").splitlines()
    stl.write_text("\n".join([*program, "TNX ON", "FON C:$02500 N:MOV S:$10000 D:$04000", "JMP NOWHERE",
                              "FON C:$02504 N:MOV S:$04000", "TIM $02510 N:999",
                              "FON C:$02520 N:NREAD S:10000 D:$04100 R:2"]) + "\n",
                   encoding="utf-8")
    plant(st / "symbols.csv", "PUMP,02120", "PUMP,02190")
    form = st / "forms" / "zz_broken.hmi"
    form.write_text(json.dumps({"form": {"title": "t", "width": 100, "height": 100, "Font": {"Size": 1}},
                                "elements": [
        {"type": "DiscreteBase", "Name": "Broken", "x": 0, "y": 0, "w": 10, "h": 10, "InAddr": "010000"},
        {"type": "NoSuchElement", "Name": "Alien", "x": 0, "y": 0, "w": 10, "h": 10},
        {"type": "AnalogBase", "Name": "Gauge", "x": 0, "y": 0, "w": 10, "h": 10, "InAddr": "04000",
         "AppMin": 0, "AppMax": 0, "PhyMin": 0, "PhyMax": 100}]}), encoding="utf-8")
    plant(st / "messages.csv", "3,1,2,", "3,1,alarm,")
    plant(st / "station.toml", "timeout = 0.5",
          'timeout = 0.5\nendpoint = "rtu:///dev/ttyS9?parity=X"\nname = "a/b"')
    toml = st / "station.toml"
    (st / "node0.stl").write_bytes(b"NOP\n\x98\n")  # neither UTF-8 nor cp1251
    tags = st / "tags.csv"
    tags.write_text(tags.read_text(encoding="utf-8") + '"' + "x" * (csv.field_size_limit() + 1) + '"\n',
                    encoding="utf-8")
    tag_line = len(tags.read_text(encoding="utf-8").splitlines())
    (st / "forms" / "zz_text.hmi").write_text('{"form": {"title": "t",}}', encoding="utf-8")
    users = [{"name": "ivanov", "role": "boss", "salt": "00", "hash": "00"}, {"name": "petrov"}]
    (st / "users.json").write_text(json.dumps({"users": users}), encoding="utf-8")
    n = len(program)
    messages = (st / "messages.csv").read_text(encoding="utf-8").splitlines()
    message = next(i for i, line in enumerate(messages, 1) if line.startswith("3,1,alarm,"))
    symbol = next(i for i, line in enumerate((st / "symbols.csv").read_text(encoding="utf-8").splitlines(), 1)
                  if line.startswith("PUMP,"))
    problems = check_station(st).problems
    said = {
        "ru": [f"{stl}:{n + 1}:1: неизвестная инструкция 'TNX'",
               f"{stl}:{n + 2}:22: S: 010000 — недопустимый адрес",
               f"{stl}:{n + 3}:5: L: метка 'NOWHERE' не определена",
               f"{stl}:{n + 4}:1: MOV нужен D: (адрес)",
               f"{stl}:{n + 5}:14: N: 999 вне 0-255",
               f"{stl}:{n + 6}:1: NREAD: узел 0: удалённый адрес: 010000 — недопустимый адрес",
               f"{st / 'symbols.csv'}:{symbol}:6: '02190' — не восьмеричное число",
               f"{form}: form: Font: размер шрифта 1 вне диапазона 4..200",
               f'{form}: элемент "Broken": InAddr: 010000 — ни бит ввода-вывода, ни бит данных (байт*8+бит)',
               f"{form}: элемент \"Alien\": type: неизвестный тип элемента 'NoSuchElement' (типы: ",
               f'{form}: элемент "Gauge": AppMax: равно AppMin (0): преобразование не определено',
               f"{st / 'messages.csv'}:{message}: type 'alarm' — не целое неотрицательное число",
               f"{st / 'users.json'}: пользователь 'ivanov': роль 'boss' — не одна из: ",
               f"{st / 'users.json'}: пользователь 'petrov': нет role, salt, hash (каждый — текст)",
               f"{toml}: nodes[0].endpoint: endpoint 'rtu:///dev/ttyS9?parity=X': "
               "parity 'X' — не N, E и не O",
               f"{toml}: nodes[0].name: 'a/b' не может содержать '/', '+', '#'",
               f"{st / 'node0.stl'}:2:0: ни UTF-8, ни cp1251 (байт 0x98)",
               f"{tags}:{tag_line}: поле длиннее {csv.field_size_limit()} символов",
               f"{st / 'forms' / 'zz_text.hmi'}:1:24: ошибка JSON: ожидается имя свойства в двойных "
               "кавычках"],
        "en": [f"{stl}:{n + 1}:1: unknown instruction 'TNX'",
               f"{stl}:{n + 2}:22: S: 010000 is not a valid address",
               f"{stl}:{n + 3}:5: L: undefined label 'NOWHERE'",
               f"{stl}:{n + 4}:1: MOV needs D: (an address)",
               f"{stl}:{n + 5}:14: N: 999 is outside 0-255",
               f"{stl}:{n + 6}:1: NREAD: node 0: remote 010000 is not a valid address",
               f"{st / 'symbols.csv'}:{symbol}:6: '02190' is not an octal number",
               f"{form}: form: Font: font size 1 is out of range 4..200",
               f'{form}: element "Broken": InAddr: 010000 is neither an I/O bit nor a data bit (byte*8+bit)',
               f"{form}: element \"Alien\": type: unknown element type 'NoSuchElement' (types: ",
               f'{form}: element "Gauge": AppMax: equals AppMin (0): the conversion is undefined',
               f"{st / 'messages.csv'}:{message}: type 'alarm' is not a non-negative whole number",
               f"{st / 'users.json'}: user 'ivanov': role 'boss' is not one of ",
               f"{st / 'users.json'}: user 'petrov': role, salt, hash missing (each a text)",
               f"{toml}: nodes[0].endpoint: endpoint 'rtu:///dev/ttyS9?parity=X': "
               "parity 'X' is not N, E or O",
               f"{toml}: nodes[0].name: 'a/b' may not hold '/', '+', '#'",
               f"{st / 'node0.stl'}:2:0: neither UTF-8 nor cp1251 text (byte 0x98)",
               f"{tags}:{tag_line}: a field is longer than {csv.field_size_limit()} characters",
               f"{st / 'forms' / 'zz_text.hmi'}:1:24: bad JSON: Expecting property name enclosed in double "
               "quotes"],
    }[language]
    for line in said:
        assert any(p.startswith(line) for p in problems), f"{line!r} not in {problems}"
    if language == "ru":
        russian_leaves_no_english(problems)


@pytest.mark.parametrize("language", ["ru", "en"])
def test_check_says_its_own_words_in_the_station_language_naming_file_and_line(tmp_path: Path, language: str,
                                                                             run_check) -> None:
    """The summary, what was found good and check's own problems in the station's `Language`, each
    problem still naming its file, key and line."""
    st = copy_demo(tmp_path / "st")
    plant(st / "station.toml", 'Language = "ru"', f'Language = "{language}"')
    plant(st / "station.toml", 'alarm_horn = "03600"', 'alarm_horn = "02200"')
    (st / "archive" / "journal.sqlite").mkdir(parents=True)  # a folder where the archive should be
    r = run_check(st)
    assert r.returncode == 1
    toml = st / "station.toml"
    line = next(i for i, text in enumerate((st / "netplc.stl").read_text(encoding="utf-8").splitlines(), 1)
                if text.startswith("YON $02200"))
    if language == "ru":
        # the archive's problem in the start's own words (a start refuses with the same)
        assert f"{toml}: Archive: {st / 'archive' / 'journal.sqlite'}: cannot open the archive: " in r.stdout
        assert f"{toml}: alarm_horn: бит 02200 пишет программа (строка {line}: " in r.stdout
        assert "найдено проблем: 2" in r.stderr
    else:
        assert f"{toml}: Archive: {st / 'archive' / 'journal.sqlite'}: cannot open the archive: " in r.stdout
        assert f"{toml}: alarm_horn: 02200 is written by the program (line {line}: " in r.stdout
        assert "2 problem(s) found" in r.stderr
