"""The plain-line reading of the STL parser (netplc/program.py `_Parser._plain`) against the general
one: a program reads to the same Program, or to the same diagnostics in the same order, whether its
plain lines take the one-match path or every line is read part by part (`parse(..., fast=False)`)."""

from __future__ import annotations

import dataclasses
import inspect

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from netplc.program import _PLAIN, LOGIC, Instr, Program, ProgramError, parse

SYMBOLS = {"TA": 0o2003, "ON": 0o3760, "W": 0o5000, "X": 0o4000}


def mostly(plain: list[str], odd: list[str]) -> st.SearchStrategy[str]:
    """A part of a line: four times in five one of the plain forms, else one the plain reading
    leaves to the general one (so that a line is often plain, or plain but for one part)."""
    return st.sampled_from(plain * -(-4 * len(odd) // len(plain)) + odd)


# the STL vocabulary, and what a line should not hold, to build lines of
INDENTS = mostly(["", " ", "\t", " \t "], ["\u00a0", "\u2003 "])
LINE_NUMBERS = mostly(
    ["", "0.0 ", "12.34\t", "00.01  "], ["1.2", "1.2:", "\u0661.\u0662 ", "3. ", ".5 ", "1..2 "]
)
LABELS = mostly(
    ["", "L1: ", "lab:\t", "L1 : ", "_x: ", "TNA: ", "C: ", "l1:  "],
    ["L1:", "L1:;", "L1:#", "a.b: ", "Пуск: ", "L1:: ", "1L: ", "L1 ;: ", "L1://"],
)
MNEMONICS = mostly(list(LOGIC), ["XYZ", "T", "TNA1", "TNA_", "ТNA", "A.B", "", "$", "TA", "TNAX"])
SEPARATORS = mostly([" ", "\t", "  "], [";", " ; ", "", "\u00a0", "\u2003", ";;", ","])
KEYS = mostly(
    ["", "", "", "C:", "c:", "N:", "n:", "L:", "l:", "S:", "d:", "R:", "X:"],
    ["C :", "C: ", "CC:", ":", "1:", "_:"],
)
VALUES = mostly(
    ["$03000", "$02000", "$03760", "03000", "3000", "$0o17", "$0O7", "0o", "0", "56", "255", "256", "-1",
     "1.5", "MOV", "mov", "ADD", "NSYNC", "NREAD", "9", "300", "ON", "TA", "ta", "TA[2]", "W", "X", "L1",
     "lab", "$09", "$", "a_b", "x-y", "$03777", "$04000", "$05000", "$077777", "$0_1", "TA]", "[1]", "-",
     "1-", "TA[" + "1" * 120 + "]"],
    ["", "TA[x]", "\u0663", "\u00b2", "+7", "1 2", "#", "//", "=", "$03000;", "a:b", "é"],
)
COMMENTS = mostly(
    ["", " ; c", "\t# c", " // c", " ;", " #", "\t//", " ; a=b", "  ;; c"],
    [";; c", "; c", "#c", "//c", ";", " / c", "\t/", " :", "/", "\u00a0;"],
)
STRAYS = mostly(
    [""],
    [":", "=", ",", "\u00a0", "[", "]", ".", "/", "$", "é", "\x00", "\ufeff", "\r", "\x1c", " ", ";", "#"],
)
WHOLE = ["", "; a comment", "# another", "// and another", "TA2 = $02004", "ON = $03761", "L2 = 12",
         "B = $9", "L1:", "  lab: ; alone", "X=", "==", "JMP L1", "JMP $0", "JMP 0", "JMP $5", "JMY lab",
         "JMN nowhere"]

PARAM = st.tuples(SEPARATORS, KEYS, VALUES)
LINE = st.tuples(INDENTS, LINE_NUMBERS, LABELS, MNEMONICS, st.integers(0, 7), st.lists(PARAM, max_size=6),
                 COMMENTS, STRAYS, st.integers(0, 80))


def line_of(parts: tuple) -> str:
    """A line of the drawn parts: the mnemonic in the drawn case, the stray character at the drawn place."""
    indent, number, label, mnemonic, case, params, comment, stray, where = parts
    mnemonic = "".join(ch.lower() if case >> i & 1 else ch for i, ch in enumerate(mnemonic))
    head = f"{indent}{number}{label}{mnemonic}"
    params_text = "".join((" " if i == 0 and sep == "" else sep) + key + value
                          for i, (sep, key, value) in enumerate(params))
    text = head + params_text + comment
    where %= len(text) + 1
    return text[:where] + stray + text[where:]


PLAIN_LIKE = LINE.map(line_of)
PROGRAMS = st.lists(st.one_of(PLAIN_LIKE, PLAIN_LIKE, PLAIN_LIKE, st.sampled_from(WHOLE)), min_size=1,
                    max_size=24).map("\n".join)
# lines a plain reading could take for plain, each but one character or one space away from one
NEAR_MISSES = "\n".join(
    ["TNA $03000 / c", "TNA $03000 /", "TNA $03000/ c", "TNA $03000#c", "TNA $03000;c", "TNA $03000 ;c",
     "TNA $03000;;c", "TNA :$03000", "TNA C::$03000", "TNA C :$03000", "L1:TNA $03000", "L1 :TNA $03000",
     "1.2TNA $03000", "1.2 L1:TNA $03000", "XYZ $03000", "TNA $03000 ,", "TNA, $03000", "TNA $03000 L1:",
     "3 TNA $03000", "3. TNA $03000", ".5 TNA $03000", "1.2.3 NOP", "TNA=$03000", "TNA = $03000",
     "T.NA $03000", "TNA\u00a0$03000", "TNA $03000\u00a0; c", "TNA $03000 \x00", "TIM $03000",
     "FON $03600", "CTR n:5", "JMP", "NOP 1", "TNA X:$03000", "SON S:$03000"]
)


def outcome(text: str, fast: bool) -> Program | list[tuple[str, int, int, str]]:
    """The Program, or every diagnostic (place and English) in order."""
    try:
        return parse(text, "p.stl", SYMBOLS, fast=fast)
    except ProgramError as e:
        return [(d.file, d.line, d.col, str(d)) for d in e.errors]


# the CI machine is loaded: generating may be slow there, which says nothing of the parser
@settings(max_examples=300, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(PROGRAMS)
@example(NEAR_MISSES)
@example("TNA $03000\nFON C:$03600 N:MOV S:$05000 D:$05002\nFON C:$03604 N:ADD $05000 $05002 $05004\nJMP 0")
@example("L1: tna c:TA[2] ; x\n0.1\tTIM $03000 N:10 N:11\nJMP L1\nJMN L2")
@example("YON $03000 $03001\nNOP X:1\nL1: FON C:$03600 N:NSYNC 10 0 7")
def test_plain_reading_is_the_general_one(text: str) -> None:
    assert outcome(text, fast=True) == outcome(text, fast=False)


def test_plain_lines_take_the_one_match():
    """The lines a program mostly holds are plain (else the property above would hold vacuously)."""
    plain = ["TNA $03760", "0.12 tfa\tc:TA ; why", "L1: TIM $03000 N:56", "FON C:$03600 N:MOV S:W D:X  // x",
             "  JMP L1", "NOP", "yon TA[3]\t# out"]
    for line in plain:
        assert _PLAIN.fullmatch(line), line
    for line in ["TA = $02003", "L1:", "TNA $03000;N:5", "TNA C: $03000", "TNA\u00a0$03000", "TNA $03000;;c"]:
        assert not _PLAIN.fullmatch(line), line


def test_instr_init_takes_the_fields():
    """Instr's written-out __init__ (netplc/program.py says why) takes every field, in order, with
    its default, and the instruction stays frozen."""
    params = list(inspect.signature(Instr).parameters.values())
    assert [(p.name, p.default) for p in params] == [
        (f.name, inspect.Parameter.empty if f.default is dataclasses.MISSING else f.default)
        for f in dataclasses.fields(Instr)]
    ins = Instr("FON", 1, 2, 3, 4, 5, 6, 7, 8, "t")
    assert [getattr(ins, f.name) for f in dataclasses.fields(Instr)] == ["FON", 1, 2, 3, 4, 5, 6, 7, 8, "t"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        ins.c = 0  # type: ignore[misc]
