"""The STL parser (docs/architecture.md section 5): what it accepts, and a `file:line:col: message` for every
kind of malformed program, never a traceback."""

from __future__ import annotations

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from netplc.functions.registry import BY_NAME, REGISTRY, FunctionSpec
from netplc.program import PROGRAM_WORDS, ProgramError, load_symbols, parse, parse_file, read_symbols
from tests.unicode_text import any_text


def errors(text: str, **kw) -> list[str]:
    with pytest.raises(ProgramError) as e:
        parse(text, source="p.stl", **kw)
    return [str(d) for d in e.value.errors]


def one_error(text: str, **kw) -> str:
    found = errors(text, **kw)
    assert len(found) == 1, found
    return found[0]


# --- what is accepted ---------------------------------------------------------------------------


def test_instructions_labels_symbols_and_comments():
    text = """; a comment line
# another
START = $02042   ; start button
0.0   TNA   C:START;
0.1   TFA $00001
lab1: TNO C:$03760
      YON $02000   ; a trailing comment
      CTR C:$02003 N:1
      TIM $03000 N:255
lab2:
      JMY lab1
      JMP 0
"""
    p = parse(text, source="p.stl")
    assert [i.op for i in p.instrs] == ["TNA", "TFA", "TNO", "YON", "CTR", "TIM", "JMY", "JMP"]
    assert p.instrs[0].c == 0o2042 and p.instrs[0].line == 4
    assert p.instrs[1].c == 1 and p.instrs[5].n == 255
    assert p.instrs[6].target == 2  # lab1 names the TNO
    assert p.instrs[7].target is None  # JMP 0 ends the scan
    assert [i.addr for i in p.instrs] == [0, 1, 2, 3, 4, 6, 8, 9]  # TIM/CTR take 2 words
    assert p.words == 10 and p.symbols["START"] == 0o2042


def test_symbols_file_and_symbol_offsets(tmp_path):
    csv = tmp_path / "symbols.csv"
    csv.write_text("name,address,comment\nTA,02003,counter TA\nTTC,$02042,input\n", encoding="utf-8")
    symbols = load_symbols(csv)
    assert symbols == {"TA": 0o2003, "TTC": 0o2042}
    p = parse("TNA TTC\nCTR TA N:1\nTNA TA[2]\nYON TA[1]", symbols=symbols)
    assert [i.c for i in p.instrs] == [0o2042, 0o2003, 0o2005, 0o2004]


def test_positional_parameters_fill_the_keys_in_order():
    p = parse("TNA $02042\nTIM $03000 7\nJMP 0")
    assert p.instrs[1].c == 0o3000 and p.instrs[1].n == 7


def test_label_at_the_end_ends_the_scan_and_numeric_jump_addresses_are_octal():
    p = parse("JMY end\nTIM $03000 N:1\nJMP 3\nend:")
    assert p.instrs[0].target == 3  # the end of the program
    assert p.instrs[2].target == 2 and p.instrs[2].op == "JMP"  # word address 3 = the JMP itself


def test_fon_takes_a_function_number_or_its_mnemonic(monkeypatch):
    spec = FunctionSpec(4247, "TESTFN", "M", "O", "D", lambda ctx, fon: None)
    monkeypatch.setitem(REGISTRY, 4247, spec)
    monkeypatch.setitem(BY_NAME, "TESTFN", spec)
    p = parse("FON C:$03000 N:testfn S:$04000 D:200 R:15\nFON $03004 N:TESTFN $04002 17 9")
    a, b = p.instrs
    assert (a.c, a.n, a.s, a.d, a.r) == (0o3000, 4247, 0o4000, 0o200, 15)  # O is octal, D decimal
    assert (b.c, b.s, b.d, b.r) == (0o3004, 0o4002, 0o17, 9)
    assert p.words == 10


def test_positional_fon_operands_fill_the_parameters_the_function_takes(monkeypatch):
    spec = FunctionSpec(4249, "DONLY", None, "M", "D", lambda ctx, fon: None)
    monkeypatch.setitem(REGISTRY, 4249, spec)
    monkeypatch.setitem(BY_NAME, "DONLY", spec)
    ins = parse("FON $03000 N:DONLY $04010 12").instrs[0]
    assert (ins.s, ins.d, ins.r) == (None, 0o4010, 12)
    ins = parse("FON $03000 N:DONLY R:5 $04010").instrs[0]
    assert (ins.d, ins.r) == (0o4010, 5)
    assert one_error("FON $03000 N:DONLY $04010 12 $04000") == (
        "p.stl:1:30: FON DONLY takes no more parameters (extra '$04000')")


def test_parse_file_names_the_file(tmp_path):
    f = tmp_path / "prog.stl"
    f.write_text("TNA $02042\nXYZ\n", encoding="utf-8")
    with pytest.raises(ProgramError) as e:
        parse_file(f)
    assert str(e.value) == f"{f}:2:1: unknown instruction 'XYZ'"
    with pytest.raises(ProgramError, match="cannot read program"):
        parse_file(tmp_path / "missing.stl")


# --- every kind of malformed program --------------------------------------------------------------


def test_unknown_mnemonic():
    assert one_error("TNA $0\n   TXA $1") == "p.stl:2:4: unknown instruction 'TXA'"
    assert one_error("T1A $1") == "p.stl:1:1: unknown instruction 'T1A'"
    hint = "p.stl:1:1: unknown instruction 'lab' (a label needs a colon: 'lab:')"
    assert one_error("lab FON C:$03000") == hint


def test_missing_parameter():
    assert one_error("TNA") == "p.stl:1:1: TNA needs C: (a bit address)"
    assert one_error("  TIM C:$03000") == "p.stl:1:3: TIM needs N: (preset 0-255)"
    assert one_error("JMP") == "p.stl:1:1: JMP needs a label"
    assert one_error("TNA C:") == "p.stl:1:5: C: has no value"


def test_extra_or_wrong_parameter():
    assert one_error("TNA $1 $2") == "p.stl:1:8: TNA takes no more parameters (extra '$2')"
    assert one_error("HLT 5") == "p.stl:1:5: HLT takes no more parameters (extra '5')"
    assert one_error("TNA N:5") == "p.stl:1:7: TNA has no parameter N:"
    assert one_error("TIM C:$03000 N:1 C:$03002") == "p.stl:1:20: parameter C: given twice"


def test_bad_number():
    assert one_error("TIM $03000 N:1x") == "p.stl:1:14: N: '1x' is not a decimal number"
    assert one_error("TIM $03000 N:²") == "p.stl:1:14: N: '²' is not a decimal number"
    assert one_error("TNA $02048") == "p.stl:1:5: C: '$02048' is not an octal address"
    assert one_error("JMP 9") == "p.stl:1:5: L: '9' is not an octal program address"
    assert one_error("FON C:$03000 N:1x") == "p.stl:1:16: N: '1x' is not a function number"


def test_unknown_symbol():
    assert one_error("TNA START") == "p.stl:1:5: C: unknown symbol 'START'"
    assert one_error("T = $02000\nTNA T[x]") == "p.stl:2:5: C: unknown symbol 'T[x]'"


def test_invalid_or_out_of_range_address():
    assert one_error("TNA $04000") == "p.stl:1:5: C: 04000 is not an I/O bit (00000-03777)"
    assert one_error("YON $010000") == "p.stl:1:5: C: 010000 is not an I/O bit (00000-03777)"
    assert one_error("CTR $03776 N:1") == "p.stl:1:5: C: CTR uses bits 03776-04000, past I/O bit 03777"
    assert one_error("JMP 1") == "p.stl:1:5: L: program address 1 is not the start of an instruction"


def test_invalid_function_operand_is_a_load_error(monkeypatch):
    spec = FunctionSpec(4248, "OPER", "M", "M", None, lambda ctx, fon: None)
    monkeypatch.setitem(REGISTRY, 4248, spec)
    monkeypatch.setitem(BY_NAME, "OPER", spec)
    for gap in ("010000", "0100000", "013777"):
        found = one_error(f"FON C:$03000 N:OPER S:${gap} D:$04000")
        assert found == f"p.stl:1:23: S: {gap} is not a valid address"
    assert one_error("FON C:$03000 N:OPER S:$04000") == "p.stl:1:1: OPER needs D: (an address)"
    assert one_error("FON C:$03000 N:OPER S:$04000 D:$04000 R:1") == "p.stl:1:41: OPER takes no R: parameter"


def test_undefined_or_duplicate_label():
    assert one_error("JMY nowhere") == "p.stl:1:5: L: undefined label 'nowhere'"
    assert one_error("a: NOP\n  a: NOP") == "p.stl:2:3: label 'a' defined twice"
    assert one_error("S = $1\nS = $2") == "p.stl:2:1: symbol 'S' defined twice"


def test_n_outside_0_255():
    assert one_error("TIM $03000 N:256") == "p.stl:1:14: N: 256 is outside 0-255"
    assert one_error("CTR $03000 N:-1") == "p.stl:1:14: N: -1 is outside 0-255"
    assert one_error("TIM $03000 N:$10") == "p.stl:1:14: N: a constant is needed here, not the address '$10'"


def test_unknown_function_number_or_name():
    assert one_error("FON C:$03000 N:5") == "p.stl:1:16: N: function 5 does not exist"
    assert one_error("FON C:$03000 N:NOSUCH") == "p.stl:1:16: N: unknown function 'NOSUCH'"


def test_several_errors_are_reported_at_once_in_line_order():
    text = "TXA $1\nTNA $04000\nTIM $03000 N:300\nJMY nowhere\nTNA $02000\n"
    assert errors(text) == [
        "p.stl:1:1: unknown instruction 'TXA'",
        "p.stl:2:5: C: 04000 is not an I/O bit (00000-03777)",
        "p.stl:3:14: N: 300 is outside 0-255",
        "p.stl:4:5: L: undefined label 'nowhere'",
    ]


def test_program_larger_than_program_memory():
    text = "NOP\n" * PROGRAM_WORDS + "JMP 0\n"
    last = PROGRAM_WORDS + 1
    assert one_error(text) == f"p.stl:{last}:1: program needs 8193 words; program memory holds 8192"


def test_bad_symbols_file(tmp_path):
    f = tmp_path / "s.csv"
    f.write_text("name,address\nA,02000\nB,0208\nA,02001\nC\n1x,02000\n", encoding="utf-8")
    with pytest.raises(ProgramError) as e:
        load_symbols(f)
    assert [str(d) for d in e.value.errors] == [
        f"{f}:3:3: '0208' is not an octal number",
        f"{f}:4:1: symbol 'A' defined twice",
        f"{f}:5:1: symbol 'C' has no address",
        f"{f}:6:1: '1x' is not a valid symbol name",
    ]
    with pytest.raises(ProgramError, match="cannot read symbols"):
        load_symbols(tmp_path / "missing.csv")


def test_symbols_name_memory_and_are_one_line_each_the_good_lines_kept(tmp_path):
    """A symbol no program uses is checked all the same: a typo there is a typo the next program
    that uses the name inherits."""
    f = tmp_path / "s.csv"
    f.write_text("A,02000\nBITS,040005\nGAP,010000\nHUGE,0" + "7" * 400 + '\n"SPL\nIT",02001\nB,04000\n'
                 "TOP,0777777\nPAST,01000000\n", encoding="utf-8")
    symbols, errors = read_symbols(f)
    assert symbols == {"A": 0o2000, "BITS": 0o40005, "B": 0o4000, "TOP": 0o777777}
    assert [str(d) for d in errors] == [
        f"{f}:3:5: 010000 names no memory: neither an I/O bit (00000-03777), a data byte (k*010000 + "
        "04000-07777) nor a data bit (byte*8 + bit)",
        f"{f}:4:6: an address of 401 characters names no memory",
        f"{f}:5:1: a quoted field runs on to line 6: a row is one line (a closing quote missing?)",
        f"{f}:9:6: 01000000 names no memory: neither an I/O bit (00000-03777), a data byte (k*010000 + "
        "04000-07777) nor a data bit (byte*8 + bit)",
    ]


LINE_PIECES = [
    "TNA", "TFA", "TNO", "TNE", "YON", "SON", "SKP", "JMP", "JMY", "HLT", "TIM", "CTR", "FON", "NOP",
    " ", " ", "\t", ";", ":", "#", "=", "$", "$0", "$04000", "$0100000", "$02042", "0", "7", "9", "²",
    "C:", "N:", "S:", "D:", "R:", "L:", "N:MOV", "N:300", "lab", "lab:", "X", "X[1]", "[", "]", "-1",
    "0.0", "\n", "\r", "\x00", "é", "ё", "Тест",
]


# up to 30 pieces, drawn as a byte each: one draw, where a list of sampled_from took two a piece
PIECES = st.binary(max_size=30).map(lambda data: "".join(LINE_PIECES[b * len(LINE_PIECES) >> 8]
                                                         for b in data))


@settings(max_examples=400, deadline=None)
@given(PIECES, any_text(max_size=40))
# a line number, a comment, a key without its value, a jump without its label: reached now and then
@example("0.0 TNA $0 ;x\nYON C: \nJMY\n", "")
def test_arbitrary_text_gives_a_program_or_a_program_error(pieces, text):
    for candidate in (pieces, text, pieces + text):
        try:
            parse(candidate, source="f.stl")
        except ProgramError as e:
            assert e.errors
            for d in e.errors:
                assert str(d).startswith(f"f.stl:{d.line}:{d.col}: ") and d.line >= 1 and d.col >= 1
