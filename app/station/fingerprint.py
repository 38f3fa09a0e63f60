"""What makes two stations of a hot-standby pair the same station: a hash of each of its files.

The standby runs the primary's program from the primary's memory the moment it takes over, so a
pair whose program, symbols, tags, messages or forms differ would change the plant's behaviour at
a switchover. The pair compares these hashes when its link comes up and refuses to pair, naming
the files that differ; `main.py check A B` compares two folders the same way before they run.
station.toml counts without the keys that must differ between the two ([redundancy] letter,
listen and partner), as parsed TOML, so a comment or a reordered key does not part a pair. The
station's name counts too, the name a folder gives when station.toml has none: the plant archive
keys both stations' records by it, and the arbiter's lease is the name's.
"""

from __future__ import annotations

import hashlib
import json
import tomllib
from pathlib import Path

from app.station.config import STATION_FILE, Station

OWN_KEYS = ("letter", "listen", "partner")  # [redundancy] keys of one station of the pair
NAME = "the station's name"  # not a file: what `differing` names when the names differ


def fingerprint(station: Station) -> dict[str, str]:
    """sha256 of each file the pair must share, by its path relative to the station folder (or
    absolute, for a file outside it)."""
    folder = station.folder
    files: dict[str, str] = {STATION_FILE: _settings_hash(station.path), NAME: station.name}
    paths = [station.NetPlcProgram, station.Symbols, station.Messages, station.Tags]
    if station.HMIload is not None:
        paths += sorted(p for p in station.HMIload.rglob("*") if p.is_file())
    for path in paths:
        if path is not None:
            name = str(path.relative_to(folder)) if path.is_relative_to(folder) else str(path)
            files[name] = _file_hash(path)
    return files


def differing(ours: dict[str, str], theirs: dict[str, str]) -> list[str]:
    """The files whose hashes differ, or that one of the two has and the other lacks."""
    return sorted(name for name in ours.keys() | theirs.keys() if ours.get(name) != theirs.get(name))


def digest(files: dict[str, str]) -> str:
    """One hash of all of them: what the pair link sends first."""
    return hashlib.sha256(json.dumps(files, sort_keys=True).encode()).hexdigest()


def _settings_hash(path: Path) -> str:
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return _file_hash(path)  # what cannot be parsed counts byte for byte
    pair = data.get("redundancy")
    if isinstance(pair, dict):
        data["redundancy"] = {k: v for k, v in pair.items() if k not in OWN_KEYS}
    return hashlib.sha256(json.dumps(data, sort_keys=True, default=str).encode()).hexdigest()


def _file_hash(path: Path) -> str:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError as e:
        return f"unreadable: {e.strerror or e}"
