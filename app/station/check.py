"""`python main.py check STATION`: every problem of a station before it is started on a plant.

It reads the station exactly as a start does (`app.station.load.load`, the runtime's own loader), so what
`check` passes a start accepts; on top, it reports what a start only journals: node host names
that do not resolve and forms that do not load; and what only the start's opening of the archive
would find (a folder, or a file that is no SQLite database, where the archive should be), in the
words the start refuses with.

Its own words (the summary, what was found good, the problems it finds itself) are said in the
station's `Language` (app/scada/words.py), the system locale's where the station cannot be read;
each still names the file, the key, the line or the element.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from app.scada.words import Words, words
from app.station.config import read_station
from app.station.fingerprint import differing, fingerprint
from app.station.load import load
from app.station.runtime import unresolved_hosts
from netplc.address import fmt_octal
from netplc.program import COIL_BITS, Program
from registrar.store import archive_problem


@dataclass
class CheckReport:
    words: Words = field(default_factory=words)  # the station's language, or the system's
    problems: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # what was found good, for the summary
    warnings: list[str] = field(default_factory=list)  # allowed, but the engineer must know

    @property
    def ok(self) -> bool:
        return not self.problems


def check_station(path: str | Path) -> CheckReport:
    station, problems = read_station(path)
    report = CheckReport(words(station.Language) if station is not None else words())
    say = report.words
    report.problems += problems
    if station is None:
        return report
    report.notes.append(say("note station", path=station.path))
    report.problems += unresolved_hosts(station)
    if problem := archive_problem(station.Archive):
        report.problems.append(f"{station.path}: Archive: {station.Archive}: cannot open the archive: "
                               f"{problem}")  # the start's words, as it refuses
    loaded = load(station)
    report.problems += loaded.problems + loaded.form_problems
    report.warnings += [w for form in loaded.forms for w in form.warnings]
    report.notes += [say.say(note) for note in loaded.notes]
    if station.alarm_horn is not None:
        report.problems += horn_written(station.path, station.alarm_horn, loaded.program, say)
    pair = station.redundancy
    if pair is not None and pair.arbiter == "none":
        report.warnings.append(say("check split brain", path=station.path))
    return report


def horn_written(path: Path, horn: int, program: Program, say: Words) -> list[str]:
    """`alarm_horn` is the station's to set between two scans: a coil of the program on it would
    fight the station, and the program's own use of the bit would be broken (an edge memory, say)."""
    return [say("check horn", path=path, bit=fmt_octal(horn), line=ins.line, text=ins.text.strip())
            for ins in program.instrs
            if ins.op in COIL_BITS and ins.c is not None and ins.c <= horn < ins.c + COIL_BITS[ins.op]]


def check_pair(path: str | Path, partner: str | Path) -> CheckReport:
    """Both stations of a hot-standby pair, and that they hold the same station: the files
    whose hashes differ are named (app/station/fingerprint.py), as the pair link refuses them."""
    report = check_station(path)
    say = report.words
    other = check_station(partner)
    report.problems += other.problems
    report.notes += other.notes
    report.warnings += [w for w in other.warnings if w not in report.warnings]
    ours, theirs = read_station(path)[0], read_station(partner)[0]
    if ours is None or theirs is None:
        return report
    for station in (ours, theirs):
        if station.redundancy is None:
            report.problems.append(say("check no pair", path=station.path))
    if ours.redundancy is not None and theirs.redundancy is not None \
            and ours.redundancy.letter == theirs.redundancy.letter:
        report.problems.append(say("check same letter", path=theirs.path, letter=ours.redundancy.letter))
    differ = differing(fingerprint(ours), fingerprint(theirs))
    if differ:
        report.problems.append(say("check differ", ours=ours.folder, theirs=theirs.folder,
                                   files=", ".join(differ)))
    else:
        report.notes.append(say("note pair", ours=ours.folder, theirs=theirs.folder))
    return report
