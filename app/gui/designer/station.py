"""What the designer takes from the station a form belongs to: names, the archive, the Modbus server.

`main.py design` takes a form or a station. A form finds its station by looking for station.toml in
its own folder and the two above (forms live in `HMIload`, normally a folder of the station);
a form without a station is still designed, with no names to complete and no live preview.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from app.scada.table import TagTable, read_tags
from app.station.config import STATION_FILE, Station, read_station
from netplc.program import ProgramError, load_symbols

TAGS_FILE = "tags.csv"
NEW_FORM = "form1.hmi"


@dataclass
class Context:
    station: Station | None
    form: Path  # the form to open (may not exist yet: a new form)
    names: dict[str, int] = field(default_factory=dict)  # symbols and tags -> address
    tags: TagTable = field(default_factory=TagTable)  # the good rows of the station's tags.csv

    @property
    def language(self) -> str:
        """The station's Language: the form's problems are said in it, as `check` says them, and
        the designer's own words follow it ("": the system locale's, a form without a station)."""
        return self.station.Language if self.station is not None else ""

    @property
    def forms(self) -> list[Path]:
        folder = self.station.HMIload if self.station is not None else None
        return sorted(folder.glob("*.hmi")) if folder is not None else []


def find_station(form: Path) -> Path | None:
    for folder in [form.parent, *list(form.parent.parents)[:2]]:
        if (folder / STATION_FILE).is_file():
            return folder / STATION_FILE
    return None


def names(station: Station) -> dict[str, int]:
    """Symbols, and tags when the station has a tags.csv (a tag may reuse a symbol's name: the
    symbol's address is kept). A file with errors gives no names: check reports it."""
    out: dict[str, int] = {}
    files = [station.folder / TAGS_FILE]
    if station.Symbols is not None:
        files.insert(0, station.Symbols)
    for path in files:
        if path.is_file():
            try:
                for name, addr in load_symbols(path).items():
                    out.setdefault(name, addr)
            except ProgramError:
                continue
    return out


def open_target(target: str | Path) -> Context:
    """The station and the form to open for `main.py design TARGET` (a form or a station)."""
    path = Path(target)
    if path.suffix.lower() == ".hmi":
        toml = find_station(path.resolve())
        station = read_station(toml)[0] if toml is not None else None
        form = path
    else:
        station, problems = read_station(path)
        if station is None:
            raise ValueError("; ".join(problems))
        folder = station.HMIload or station.folder / "forms"
        existing = sorted(folder.glob("*.hmi")) if folder.is_dir() else []
        form = existing[0] if existing else folder / NEW_FORM
    if station is None:
        return Context(None, form)
    found = names(station)
    return Context(station, form, found, tags(station, found))


def tags(station: Station, symbols: dict[str, int]) -> TagTable:
    """The station's tags (their good rows: check reports the others), for the tag browser and for
    elements to take their conversion, unit and limits from."""
    if station.Tags is None or not station.Tags.is_file():
        return TagTable()
    return read_tags(station.Tags, symbols)[0]
