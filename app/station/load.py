"""Everything a station reads before it starts: symbols, the NetPlc program, the simulated nodes'
programs, the message catalog, the tags, the users and the forms; and whether the optional parts
its configuration asks for are installed (`extras.py`). The runtime's start and `check`
both call `load`, so `check` reports exactly what a start would refuse.

Each part is read even when an earlier one failed, the good lines of a broken symbols file are
kept and a broken program is read again without its bad lines, so the checks that need a whole
program (the nodes of NREAD/NWRITE) still run on the rest: an engineer gets the whole list at
once, each line naming its file and place. Forms are apart: a form that does not load is a
problem the station runs with (the other forms open; its behaviour is missing and said so), never
a reason not to start.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from app.authority.policy import VIEWER
from app.authority.users import USERS_FILE, Users, UsersFileError
from app.scada.table import TagTable, read_tags
from app.scada.words import Phrase, Words, phrase, words
from app.station.config import Station
from app.station.extras import station_problems
from netplc.exchange import check_program_nodes
from netplc.parsecache import ParseCache, parse_file_cached
from netplc.program import Program, ProgramError, load_symbols, parse, parse_file, read_symbols
from netplc.textfile import MISSING, TextFileError, confine, file_problem, read_text
from registrar.catalog import Catalog, CatalogError

if TYPE_CHECKING:
    from hmi_forms.form import Form

RECOVERY_ROUNDS = 5


@dataclass
class Loaded:
    symbols: dict[str, int] = field(default_factory=dict)
    catalog: Catalog = field(default_factory=Catalog)
    program: Program = field(default_factory=lambda: parse("", source="<no program>"))
    node_programs: list[Program] = field(default_factory=list)  # one per station.simulators, in order
    tags: TagTable = field(default_factory=TagTable)  # the good rows of tags.csv
    forms: list[Form] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)  # each one stops a start
    form_problems: list[str] = field(default_factory=list)  # forms that did not load
    notes: list[Phrase] = field(default_factory=list)  # what was found good, for check's summary


def load(station: Station, parse_cache: Path | None = None) -> Loaded:
    """What the station reads; with `parse_cache` (a start's, not `check`'s: check writes nothing),
    the parsed programs are kept in that folder for the next start (netplc/parsecache.py)."""
    out = Loaded()
    say = words(station.Language)
    out.symbols = _symbols(station.Symbols, out, say)
    cache = ParseCache(parse_cache) if parse_cache is not None else None
    program = _program(station, out, cache, say)
    if program is not None:
        out.problems += [d.said(say) for d in check_program_nodes(program, station.nodes)]
    for sim in station.simulators:
        try:
            p = _parse(sim.program, load_symbols(sim.symbols) if sim.symbols else {}, cache)
        except ProgramError as e:
            out.problems += [d.said(say) for d in e.errors]
            continue
        out.node_programs.append(p)
        out.notes.append(phrase("note simulator", node=sim.node, program=sim.program.name,
                                instrs=len(p.instrs)))
    if station.Messages is not None:
        try:
            out.catalog = Catalog.load(station.Messages)
            out.notes.append(phrase("note messages", file=station.Messages.name, n=len(out.catalog)))
        except CatalogError as e:
            out.problems += e.said(say)
    if station.Tags is not None:
        out.tags, problems = read_tags(station.Tags, out.symbols, say)
        out.problems += problems
        out.notes.append(phrase("note tags", file=station.Tags.name, n=len(out.tags.tags),
                                alarms=len(out.tags.alarms)))
    _users(station, out)
    _state_files(station, out)
    out.problems += station_problems(station)  # OPC UA, MQTT or the plant archive without its extra
    out.forms, out.form_problems = load_station_forms(station, out.symbols, out.tags)
    if station.HMIload is not None:
        out.notes.append(phrase("note forms", folder=station.HMIload, n=len(out.forms)))
    return out


def load_station_forms(station: Station, symbols: dict[str, int],
                       tags: TagTable | None = None) -> tuple[list[Form], list[str]]:
    """The forms of HMIload (fresh models each call: the runtime's and each view's are their own),
    and the problems of those that did not load. Their addresses may name `tags`."""
    if station.HMIload is None:
        return [], []
    from hmi_forms.form import load_forms  # the form code loads only for a station that has forms

    return load_forms(station.HMIload, symbols, station=station.folder, allow_outside=station.allow_outside,
                      tags=tags, say=words(station.Language))


def _symbols(path: Path | None, out: Loaded, say: Words) -> dict[str, int]:
    """The symbols; with errors, those of the good lines, so the program is checked against them."""
    if path is None:
        return {}
    symbols, errors = read_symbols(path)
    out.problems += [d.said(say) for d in errors]
    return symbols


def _users(station: Station, out: Loaded) -> None:
    """users.json, and the user [operator] default_user names: whoever sits at the workstation
    without logging in acts as that user, so it must exist and be a viewer."""
    path = station.folder / USERS_FILE
    try:
        if not station.allow_outside:
            confine(path, station.folder)
        users = Users(station.folder)
    except TextFileError as e:
        out.problems.append(e.said(words(station.Language)))
        return
    except UsersFileError as e:
        out.problems += e.said(words(station.Language))
        return
    name = station.operator.default_user
    user = users.get(name)
    key = f"{station.path}: operator.default_user"
    say = words(station.Language)
    if name and user is None:
        out.problems.append(f"{key}: " + say("users no default", name=name, path=path))
    elif user is not None and user.role != VIEWER:
        out.problems.append(f"{key}: " + say("users default role", name=name, role=user.role))
    elif users.users:
        out.notes.append(phrase("note users", file=USERS_FILE, n=len(users.users)) if not name else
                         phrase("note users default", file=USERS_FILE, n=len(users.users), name=name))


def _state_files(station: Station, out: Loaded) -> None:
    """The files the station writes and reads back at its next start (retentive memory, retained
    forces): a folder, FIFO or device there would be read without end or never saved."""
    files = [("Retain", station.Retain)] + [("RetainForces", station.forces_file)] * station.RetainForces
    for key, path in files:
        if (why := file_problem(path)) not in (None, MISSING):
            out.problems.append(f"{station.path}: {key}: {path} {why}")


def _parse(path: Path, symbols: dict[str, int], cache: ParseCache | None) -> Program:
    return parse_file(path, symbols) if cache is None else parse_file_cached(path, symbols, cache)


def _program(station: Station, out: Loaded, cache: ParseCache | None, say: Words) -> Program | None:
    """The program (none when NetPlcLoad is false); with errors, the program without its bad lines
    (line numbers kept) for the checks that need a whole program, and `out.program` stays empty."""
    path = station.NetPlcProgram
    if not station.NetPlcLoad or path is None:
        return None
    try:
        program = _parse(path, out.symbols, cache)
    except ProgramError as e:
        out.problems += [d.said(say) for d in e.errors]
        return _recovered(path, out.symbols, {d.line for d in e.errors})
    out.program = program
    out.notes.append(phrase("note program", file=path.name, instrs=len(program.instrs), words=program.words))
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
