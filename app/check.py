"""`python main.py check STATION`: every problem of a station before it is started on a plant.

Each part is checked even when an earlier one failed (a broken program does not hide a broken
form), so an engineer gets the whole list at once, each line naming its file and place.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from app.config import Station, read_station
from app.runtime import load_simulated_program, node_configs, unresolved_hosts
from hmi_forms.form import load_forms
from netplc.exchange import check_program_nodes
from netplc.program import Program, ProgramError, load_symbols, parse, parse_file
from netplc.textfile import TextFileError, read_text
from registrar.catalog import Catalog, CatalogError

RECOVERY_ROUNDS = 5


@dataclass
class CheckReport:
    problems: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # what was found good, for the summary

    @property
    def ok(self) -> bool:
        return not self.problems


def check_station(path: str | Path) -> CheckReport:
    report = CheckReport()
    station, problems = read_station(path)
    report.problems += problems
    if station is None:
        return report
    report.notes.append(f"station {station.path}")
    report.problems += unresolved_hosts(station)
    symbols = _symbols(station.Symbols, report)
    program = _program(station, symbols, report)
    if program is not None:
        report.problems += [str(d) for d in check_program_nodes(program, node_configs(station.nodes))]
    for sim in station.simulators:
        try:
            p = load_simulated_program(sim.program, sim.symbols)
            report.notes.append(f"node {sim.node} simulator program {sim.program.name}: "
                                    f"{len(p.instrs)} instructions")
        except ProgramError as e:
            report.problems += [str(d) for d in e.errors]
    if station.Messages is not None:
        try:
            catalog = Catalog.load(station.Messages)
            report.notes.append(f"messages {station.Messages.name}: {len(catalog)} texts")
        except CatalogError as e:
            report.problems += list(e.problems)
    if station.HMIload is not None:
        forms, problems = load_forms(station.HMIload, symbols, station=station.folder)
        report.problems += [str(p) for p in problems]
        report.notes.append(f"forms in {station.HMIload}: {len(forms)} loaded")
    return report


def _symbols(path: Path | None, report: CheckReport) -> dict[str, int]:
    """The symbols; with errors, those of the good lines, so the program is checked against them."""
    if path is None:
        return {}
    try:
        return load_symbols(path)
    except ProgramError as e:
        report.problems += [str(d) for d in e.errors]
        bad = {d.line for d in e.errors}
    try:
        text = _blank_lines(path, bad)
    except TextFileError:
        return {}  # already reported
    with tempfile.TemporaryDirectory() as tmp:
        good = Path(tmp) / path.name
        good.write_text(text, encoding="utf-8")
        try:
            return load_symbols(good)
        except ProgramError:
            return {}


def _program(station: Station, symbols: dict[str, int], report: CheckReport) -> Program | None:
    """The program; with errors, the program without its bad lines (line numbers kept), so the
    checks that need a whole program (nodes of NREAD/NWRITE) still run on the rest."""
    path = station.NetPlcProgram
    if not station.NetPlcLoad or path is None:
        return None
    try:
        program = parse_file(path, symbols)
    except ProgramError as e:
        report.problems += [str(d) for d in e.errors]
        return _recovered(path, symbols, {d.line for d in e.errors})
    report.notes.append(f"program {path.name}: {len(program.instrs)} instructions, {program.words} words")
    return program


def _recovered(path: Path, symbols: dict[str, int], bad: set[int]) -> Program | None:
    for _ in range(RECOVERY_ROUNDS):  # removing a line can break another (a label it defined)
        try:
            return parse(_blank_lines(path, bad), source=str(path), symbols=symbols)
        except TextFileError:
            return None  # already reported
        except ProgramError as e:
            more = {d.line for d in e.errors} - bad
            if not more:
                return None
            bad |= more
    return None


def _blank_lines(path: Path, lines: set[int]) -> str:
    text = read_text(path).splitlines()
    return "\n".join("" if i in lines else line for i, line in enumerate(text, start=1))
