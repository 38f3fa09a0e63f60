"""`main.py archive backup STATION DEST` and `main.py archive restore BACKUP STATION`.

A backup is taken while the station runs and is a station folder itself: the station's files
(station.toml, programs, symbols, messages, tags, forms and their pictures, users.json, the OPC UA
certificates and trust list: every file of the folder but the log, the lock and what the station
derives, such as the compiled and parsed program) at their places, and what the station writes while it
runs, each copied so that it is whole and of one moment: the retentive memory (the newest
complete save, as a restart would take it), the retained forces, the alarm states and the
journal (SQLite's online backup API, registrar/backup.py; last, so that the journal holds at
least what the retentive memory does). `backup.json` lists them and is written last: a folder
without it is not a backup. Files the station keeps outside its folder are held under
`outside/`, and restored to where the restored station.toml puts them.

A restore refuses to write into a running station (its `station.lock`, app/station/lock.py) and
holds that lock while it writes, so no station starts on half a restore. It replaces the files
the backup holds; the retentive memory, forces, alarm states and journal become the backup's
(what the station wrote since is gone, and a state file the backup has none of is removed, so
that no state of another moment mixes in); other files of the folder are kept and named.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import shutil
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from app import __version__
from app.logs import LOG_DIR
from app.scada.station import STATE_FILE as ALARM_STATE_FILE
from app.station.config import STATION_FILE, Station, read_station
from app.station.lock import LOCK_FILE, StationLock
from app.station.runtime import CODE_CACHE, PARSE_CACHE
from registrar.backup import Copied, copy_database
from registrar.retain import newest_save, save_files

MANIFEST = "backup.json"
FORMAT = 1
OUTSIDE = "outside"  # in a backup: the state files the station keeps outside its folder
SQLITE_SIDES = ("-wal", "-shm", "-journal")  # what SQLite keeps beside a database


class BackupError(Exception):
    """A backup or a restore that cannot be made: names the folder or file and why."""


@dataclass
class Report:
    files: list[str] = field(default_factory=list)  # station files, relative to the folder
    state: dict[str, str] = field(default_factory=dict)  # role -> its place in the backup
    journal: Copied | None = None
    notes: list[str] = field(default_factory=list)  # what was left out or kept, and why


def state_files(station: Station) -> dict[str, Path]:
    """What the station writes while it runs, by role: copied each in its own way, never as a file
    of the folder."""
    return {"retain": station.Retain, "forces": station.forces_file,
            "alarms": station.Archive.with_name(ALARM_STATE_FILE), "journal": station.Archive}


def _beside(role: str, path: Path) -> list[Path]:
    """The files that go with a state file and are no part of a backup (SQLite's WAL, a save
    being written, the previous save)."""
    if role in ("alarms", "journal"):
        return [path.with_name(path.name + side) for side in SQLITE_SIDES]
    if role == "retain":
        return [file for used, file in save_files(path) if used != "current"]
    return [path.with_name(path.name + ".tmp")]


def _derived(station: Station) -> set[Path]:
    """What a backup leaves out of the folder: the state files (copied their own way) and what
    goes with them, the log, the lock and the compiled and parsed program (made again at start)."""
    archive = station.Archive.parent
    out = {station.folder / LOG_DIR, station.folder / LOCK_FILE, archive / CODE_CACHE, archive / PARSE_CACHE}
    for role, path in state_files(station).items():
        out.update([path, *_beside(role, path)])
    return out


def _station_files(station: Station, notes: list[str]) -> Iterator[Path]:
    """The station's files in its folder, relative to it (a link to a file counts as that file)."""
    skip = _derived(station)
    for root, dirs, files in os.walk(station.folder):
        here = Path(root)
        for name in sorted(dirs):
            path = here / name
            if path in skip or name == "__pycache__":
                dirs.remove(name)
            elif path.is_symlink():
                notes.append(f"{path}: a link to a folder, not followed")
                dirs.remove(name)
        for name in sorted(files):
            path = here / name
            if path in skip:
                continue
            if not path.is_file():
                notes.append(f"{path}: not a regular file, left out")
                continue
            yield path.relative_to(station.folder)


def _outside_inputs(station: Station) -> list[str]:
    """Station inputs that `allow_outside` lets live outside the folder: not in a backup."""
    inputs = {"NetPlcProgram": station.NetPlcProgram, "Symbols": station.Symbols,
              "Messages": station.Messages, "Tags": station.Tags, "HMIload": station.HMIload,
              "mqtt.ca_file": station.mqtt.ca_file}
    for i, sim in enumerate(station.simulators):
        inputs.update({f"simulators[{i}].program": sim.program, f"simulators[{i}].symbols": sim.symbols})
    return [f"{key}: {path} is outside the station folder: not in the backup"
            for key, path in inputs.items() if path is not None and not path.is_relative_to(station.folder)]


def _read(path: str | Path) -> Station:
    station, problems = read_station(path)
    if station is None:
        raise BackupError("; ".join(problems))
    return station


def _in_backup(station: Station, role: str, path: Path) -> str:
    if path.is_relative_to(station.folder):
        return path.relative_to(station.folder).as_posix()
    return f"{OUTSIDE}/{role}/{path.name}"


def backup(station_path: str | Path, dest: str | Path, *, pages: int | None = None,
           pause: float | None = None) -> Report:
    """Back the station up into `dest`, a new or empty folder, while it runs or not."""
    station = _read(station_path)
    dest = Path(dest).absolute()
    if dest.is_relative_to(station.folder):
        raise BackupError(f"{dest}: inside the station folder {station.folder}: a backup goes elsewhere")
    if dest.exists() and (not dest.is_dir() or any(dest.iterdir())):
        raise BackupError(f"{dest}: exists and is not an empty folder: a backup goes into a new one")
    dest.mkdir(mode=0o700, parents=True, exist_ok=True)  # it holds users.json and the OPC UA key
    report = Report()
    for rel in _station_files(station, report.notes):
        (dest / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(station.folder / rel, dest / rel)
        report.files.append(rel.as_posix())
    for role, path in state_files(station).items():
        target = dest / _in_backup(station, role, path)
        target.parent.mkdir(parents=True, exist_ok=True)
        if role == "retain":
            blob = newest_save(path)
            if blob is None:
                continue
            target.write_bytes(blob)
        elif role == "forces":
            try:
                shutil.copy2(path, target)
            except FileNotFoundError:
                continue
        elif not path.is_file():
            continue
        else:
            copied = copy_database(path, target, **_steps(pages, pause))
            if role == "journal":
                report.journal = copied
        report.state[role] = _in_backup(station, role, path)
    report.notes += _outside_inputs(station)
    manifest = {"format": FORMAT, "station": station.name, "from": str(station.path),
                "made": dt.datetime.now().astimezone().isoformat(timespec="seconds"),
                "version": __version__, "files": report.files, "state": report.state}
    (dest / MANIFEST).write_text(json.dumps(manifest, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return report


def _steps(pages: int | None, pause: float | None) -> dict[str, float]:
    return {k: v for k, v in (("pages", pages), ("pause", pause)) if v is not None}


def _manifest(folder: Path) -> dict:
    try:
        manifest = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise BackupError(f"{folder}: not a backup: no {MANIFEST} (a backup that did not finish has none)") \
            from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise BackupError(f"{folder / MANIFEST}: cannot be read: {e}") from None
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise BackupError(f"{folder / MANIFEST}: not a backup of format {FORMAT}")
    files, state = manifest.get("files"), manifest.get("state")
    if not (isinstance(files, list) and isinstance(state, dict)
            and all(isinstance(f, str) for f in [*files, *state.values()])):
        raise BackupError(f"{folder / MANIFEST}: its files and state are not lists of names")
    if STATION_FILE not in files:
        raise BackupError(f"{folder / MANIFEST}: holds no {STATION_FILE}")
    for rel in [*files, *state.values()]:  # a backup is input: nothing of it may land elsewhere
        path = Path(rel)
        if path.is_absolute() or ".." in path.parts or not (folder / path).is_file():
            raise BackupError(f"{folder / MANIFEST}: {rel!r} is not a file of the backup")
    return manifest


def _replace(source: Path, target: Path) -> None:
    """`target` becomes a copy of `source` at once (copied beside it, then renamed over it)."""
    target.parent.mkdir(parents=True, exist_ok=True)
    part = target.with_name(target.name + ".restoring")
    shutil.copy2(source, part)
    os.replace(part, target)


def restore(backup_folder: str | Path, station_path: str | Path) -> Report:
    """Restore the backup into the station at `station_path` (a folder or its station.toml; made
    when missing); StationRunning when a station runs there."""
    source = Path(backup_folder).absolute()
    manifest = _manifest(source)
    path = Path(station_path).absolute()
    folder = path.parent if path.suffix == ".toml" else path
    folder.mkdir(parents=True, exist_ok=True)
    report = Report()
    with StationLock(folder):
        for rel in manifest["files"]:
            _replace(source / rel, folder / rel)
            report.files.append(rel)
        station = _read(folder / STATION_FILE)
        for role, target in state_files(station).items():
            for stale in [target, *_beside(role, target)]:
                stale.unlink(missing_ok=True)
            if role in manifest["state"]:
                _replace(source / manifest["state"][role], target)
                report.state[role] = manifest["state"][role]
        restored = {Path(rel) for rel in report.files}
        report.notes += [f"{folder / rel}: kept (not in the backup)" for rel in _station_files(station, [])
                         if rel not in restored]
    return report


def describe(report: Report) -> list[str]:
    """The lines `main.py archive backup` and `restore` print."""
    lines = [f"{len(report.files)} station files"]
    for role, rel in report.state.items():
        j = report.journal if role == "journal" else None
        how = f" ({j.pages} pages in {j.steps} steps, {j.seconds:.1f} s)" if j is not None else ""
        lines.append(f"{role}: {rel}{how}")
    return lines + report.notes
