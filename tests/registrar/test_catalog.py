from pathlib import Path

import pytest

from app.station.config import DEMO_STATION
from registrar.catalog import Catalog, CatalogError, Message

EXAMPLE = DEMO_STATION / "messages.csv"


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "messages.csv"
    path.write_text(text, encoding="utf-8")
    return path


def test_demo_catalog_loads_with_cyrillic_texts():
    catalog = Catalog.load(EXAMPLE)
    assert catalog.get(3) == Message(3, 1, 2, "Уровень выше 90 %")
    assert catalog.text_for(1) == "Пуск нажат"
    assert len(catalog) >= 4


def test_header_is_optional_and_commas_stay_in_the_text(tmp_path):
    catalog = Catalog.load(write(tmp_path, '7,2,1,Насос 1, перегрев\n8,2,3,"Авария, стоп"\n\n# note\n'))
    assert catalog.text_for(7) == "Насос 1, перегрев"
    assert catalog.get(8) == Message(8, 2, 3, "Авария, стоп")


def test_unknown_number_has_a_text_saying_so():
    text = Catalog().text_for(42)
    assert "42" in text and "unknown" in text
    assert Catalog().get(42) is None


def test_errors_name_file_and_line(tmp_path):
    path = write(tmp_path, "number,group,type,text\n1,1,0,ok\nx,1,0,bad number\n2,1,7,bad type\n"
                           "1,1,0,again\n3,1\n4,1,0,\n")
    with pytest.raises(CatalogError) as info:
        Catalog.load(path)
    problems = info.value.problems
    assert [p.split(": ", 1)[0] for p in problems] == [f"{path}:{n}" for n in (3, 4, 5, 6, 7)]
    assert "'x'" in problems[0]
    assert "type 7" in problems[1]
    assert "line 2" in problems[2]
    assert "4 field" not in problems[3] and "2 field" in problems[3]
    assert "no text" in problems[4]


def test_missing_or_undecodable_file_is_a_catalog_error(tmp_path):
    with pytest.raises(CatalogError, match="cannot read"):
        Catalog.load(tmp_path / "none.csv")
    bad = tmp_path / "bad.csv"
    bad.write_bytes("1,1,0,Пуск\n2,1,0,".encode("cp1251") + b"\x98\n")  # 0x98: not cp1251 either
    with pytest.raises(CatalogError) as info:
        Catalog.load(bad)
    assert info.value.problems == [f"{bad}:2: neither UTF-8 nor cp1251 text (byte 0x98)"]


def test_utf8_with_or_without_bom_else_cp1251(tmp_path):
    for name, data in (("utf8.csv", "1,1,0,Пуск\n".encode()), ("bom.csv", "1,1,0,Пуск\n".encode("utf-8-sig")),
                       ("cp1251.csv", "1,1,0,Пуск\n".encode("cp1251"))):
        (tmp_path / name).write_bytes(data)
        assert Catalog.load(tmp_path / name).text_for(1) == "Пуск", name


@pytest.mark.parametrize(("line", "problem"), [
    (f"{2**63},1,0,big", f"number {2**63} is past {2**63 - 1}"),
    ("-1,1,0,negative", "number '-1' is not a non-negative whole number"),
    (f"1,{10**30},0,big group", "group 1000000000000000000000000000000 is past"),
    ("9" * 5000 + ",1,0,huge", "number '99999999999"),
    ("²,1,0,superscript", "number '²' is not"),
    ("1,1,0," + "x" * 140_000, "a field is longer than 131072 characters"),
])
def test_numbers_the_archive_cannot_hold_and_huge_fields_are_named(tmp_path, line, problem):
    path = write(tmp_path, f"0,1,0,fine\n{line}\n3,1,0,after\n")
    with pytest.raises(CatalogError) as info:
        Catalog.load(path)
    assert len(info.value.problems) == 1
    assert info.value.problems[0].startswith(f"{path}:2: {problem}"), info.value.problems
