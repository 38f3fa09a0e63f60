"""`python main.py check STATION`: every problem of a station before it is started on a plant.

It reads the station exactly as a start does (`app.station.load.load`, the runtime's own loader), so what
`check` passes a start accepts; on top, it reports what a start only journals: node host names
that do not resolve and forms that do not load; and what only the start's opening of the archive
would find (a folder, or a file that is no SQLite database, where the archive should be), in the
words the start refuses with.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from app.station.config import read_station
from app.station.load import load
from app.station.runtime import unresolved_hosts
from registrar.store import archive_problem


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
    if problem := archive_problem(station.Archive):
        report.problems.append(f"{station.path}: Archive: {station.Archive}: cannot open the archive: "
                               f"{problem}")
    loaded = load(station)
    report.problems += loaded.problems + loaded.form_problems
    report.notes += loaded.notes
    return report
