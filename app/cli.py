"""The station's command line: the workstation, the headless runtime, the viewer, check, simulate.

`python main.py [STATION]` must keep working as the manual's "open the server with its forms", so
the station is an optional positional argument of the top level and the other commands are
recognised by their first word instead of argparse sub-commands (which cannot share a level with
an optional positional).
"""

from __future__ import annotations

import argparse
import signal
import sqlite3
import sys
import time
from pathlib import Path

from app import __version__, logs
from app.logs import LEVELS
from app.station.config import DEMO_STATION
from netplc import interruptible
from registrar.plant.url import is_url

COMMANDS = ("view", "check", "simulate", "alarms-report", "design", "monitor", "console", "archive", "users",
            "opcua", "redundancy")


def _main_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python main.py",
        description="NetPlc Station: runs a station (NetPlc program, exchange with PLC nodes, archive) "
                    "and shows its HMI forms.",
        epilog="other commands: view [ARCHIVE] (offline journal viewer), check STATION (validate a "
               "station), simulate PROGRAM.stl (a simulated CPU-165 node), alarms-report ARCHIVE --day "
               "DD_MM_YYYY (alarm-system health), design [FORM.hmi | STATION] (the form designer), "
               "monitor opc.tcp://HOST:PORT/PATH | STATION_OR_HOST:PORT (the program monitor of a running "
               "station), console opc.tcp://HOST:PORT/PATH (a remote operator console of a running "
               "station), archive migrate "
               "ARCHIVE.sqlite postgresql://... (copy an archive into the plant archive), "
               "users (the station's users and roles), opcua trust STATION THUMBPRINT (trust an OPC UA "
               "client's certificate), redundancy status STATION|HOST:PORT (a hot-standby pair's "
               "station); each takes --help.",
    )
    p.add_argument("station", nargs="?", default=str(DEMO_STATION),
                   help="station folder or its station.toml (default: the demo station)")
    p.add_argument("--version", action="version", version=f"netplc-station {__version__}")
    p.add_argument("--no-gui", action="store_true", help="run headless, printing a status line")
    p.add_argument("--fullscreen", action="store_true",
                   help="the operator mode: the workstation full screen, no window chrome "
                        "(also [operator] fullscreen in station.toml)")
    p.add_argument("--duration", type=float, metavar="S",
                   help="with --no-gui: stop after S seconds (default: until SIGINT/SIGTERM)")
    p.add_argument("--status-every", type=float, default=5.0, metavar="S",
                   help="with --no-gui: seconds between status lines (default 5)")
    p.add_argument("--log-level", choices=LEVELS, default="WARNING",
                   help="what is logged to stderr (default WARNING; any command takes it); a running "
                        "station also logs INFO and above to log/station.log in its folder")
    return p


def _view_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python main.py view",
                                description="Open an archive read-only: records by day, filters, "
                                            "series plots, CSV export. No station needs to run.")
    p.add_argument("archive", nargs="?",
                   help="archive file (journal.sqlite), a station folder (default: the demo station's), "
                        "or a plant archive postgresql://user@host:5432/plant")
    return p


def _archive_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python main.py archive",
                                description="Archive tools. migrate: copy a station's SQLite archive into "
                                            "the plant archive on PostgreSQL; run it again and it copies "
                                            "only what is not there yet. backup: copy a station, running "
                                            "or not, into a new folder. restore: put a backup back into "
                                            "a station that is not running.")
    sub = p.add_subparsers(dest="action", required=True)
    b = sub.add_parser("backup", help="copy a station (its files, users, retentive memory, alarm states "
                                      "and journal), while it runs or not")
    b.add_argument("station", help="station folder or its station.toml")
    b.add_argument("dest", help="the backup's folder: a new or empty one")
    r = sub.add_parser("restore", help="put a backup back into a station that is not running")
    r.add_argument("backup", help="the backup's folder")
    r.add_argument("station", help="station folder (made when missing) or its station.toml")
    m = sub.add_parser("migrate", help="copy a station's archive into the plant archive")
    m.add_argument("source", help="the station folder (or its station.toml), or its archive file "
                                  "(journal.sqlite)")
    m.add_argument("url", help="the plant archive: postgresql://user@host:5432/plant (password in "
                               "PGPASSWORD or ~/.pgpass)")
    m.add_argument("--station", help="the station's name in the plant archive (default: `name` of the "
                                     "station.toml whose Archive it is, as its forwarder names it; else "
                                     "the name the archive keeps)")
    return p


def _check_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python main.py check",
                                description="Validate a station: station.toml, NetPlc program, symbols, "
                                            "simulator programs, messages and every form. Prints all "
                                            "problems; exit status 1 if there are any.")
    p.add_argument("station", help="station folder or its station.toml")
    p.add_argument("partner", nargs="?", help="the other station of a hot-standby pair: both are "
                                              "checked and must hold the same files")
    p.add_argument("--partner", dest="partner_option", metavar="STATION", help="the same as PARTNER")
    return p


def _redundancy_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python main.py redundancy",
                                description="The state of one station of a hot-standby pair, asked over "
                                            "its pair link: letter, role, partner, link, last takeover, "
                                            "lag in scans. Exit status 1 when it does not answer.")
    p.add_argument("action", choices=["status"])
    p.add_argument("target", help="the station's folder (its [redundancy] listen) or HOST:PORT of its link")
    return p


def run_redundancy(target: str) -> int:
    from app.scada.words import words
    from app.station.config import read_station
    from app.station.mirror import LinkError
    from app.station.pair import query

    address, say = target, words()  # the station's language where its folder is named
    if Path(target).exists():
        station, problems = read_station(target)
        if station is not None:
            say = words(station.Language)
        if station is None or station.redundancy is None:
            print("\n".join(problems) or say("no redundancy", target=target), file=sys.stderr)
            return 1
        address = station.redundancy.listen
    try:
        status = query(address)
    except (OSError, LinkError, ValueError) as e:
        print(say("no pair answer", address=address, error=e), file=sys.stderr)
        return 1
    for key in ("letter", "role", "partner", "link", "last_takeover", "lag", "switchovers"):
        value = status.get(key)
        if key == "link":
            value = say("link is up" if value else "link is down")
        elif key == "role" and value in ("starting", "primary", "standby"):
            value = say(f"role {value}")
        print(f"{say(f'status {key}')}: {value if value not in ('', None) else '-'}")
    return 0


def _alarms_report_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python main.py alarms-report",
                                description="Alarm-system health of one day as ISA-18.2 measures it: alarms "
                                            "per 10 minutes and floods, the 10 most frequent alarms, "
                                            "chattering and stale alarms. Reads the archive read-only.")
    p.add_argument("archive", help="archive file (journal.sqlite)")
    p.add_argument("--day", required=True, metavar="DD_MM_YYYY", help="the day, as its table is named")
    return p


def _design_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python main.py design",
                                description="The form designer: place elements, edit their properties, "
                                            "see the form's problems, preview it live against the running "
                                            "station, and save the .hmi file.")
    p.add_argument("target", nargs="?", default=str(DEMO_STATION),
                   help="a form (FORM.hmi; a new one if it does not exist) or a station folder, whose "
                        "first form opens (default: the demo station)")
    p.add_argument("--screenshot", metavar="PNG",
                   help="render the designer at 1366x768 to PNG and exit")
    return p


def _monitor_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python main.py monitor",
                                description="The Program view of a running station: the listing with live "
                                            "states and a watch table. Over the station's OPC UA endpoint "
                                            "as a user of that station (a login dialog), who writes tags, "
                                            "forces and steps as far as the station lets them; over its "
                                            "Modbus server read-only (Modbus has no users).")
    p.add_argument("target", help="opc.tcp://HOST:PORT/PATH of the station's OPC UA endpoint; or, read-only "
                                  "over Modbus, a station folder or station.toml (its program, symbols and "
                                  "Modbus port) or HOST:PORT of a NetPlc Modbus server")
    p.add_argument("--program", metavar="PROGRAM", help="the program to list: PROGRAM.stl, or the station "
                                                        "folder for its program, symbols and tags")
    p.add_argument("--user", help="over OPC UA, the user to log in as (the dialog asks the password; when "
                                  "stdin is not a terminal, its first line is the password)")
    _partner_option(p, "over OPC UA, ", "monitor")
    return p


def _partner_option(p: argparse.ArgumentParser, over: str, what: str) -> None:
    """--partner of a client of a hot-standby pair: it follows the station that leads."""
    p.add_argument("--partner", metavar="URL", default="",
                   help=f"{over}the endpoint of the other station of a hot-standby pair: the {what} follows "
                        "whichever leads (its certificate trusted by a console or monitor of it before)")


def _console_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python main.py console",
                                description="A remote operator console of a running station: its forms, "
                                            "alarms and commands over the station's OPC UA endpoint, as a "
                                            "user of that station (a login dialog); no NetPlc, exchange or "
                                            "archive of its own.")
    p.add_argument("url", help="opc.tcp://HOST:PORT/PATH of the station's OPC UA endpoint")
    p.add_argument("--user", help="the user to log in as (the dialog asks the password; when stdin is not "
                                  "a terminal, its first line is the password)")
    _partner_option(p, "", "console")
    return p


def _users_parser() -> argparse.ArgumentParser:
    from app.authority.policy import ROLES

    p = argparse.ArgumentParser(prog="python main.py users",
                                description="The station's users and roles (users.json in the station "
                                            "folder: salted scrypt hashes, never the passwords). The "
                                            "password is asked twice on a terminal, else read as one "
                                            "line from standard input.")
    p.add_argument("--station", default=str(DEMO_STATION),
                   help="station folder or its station.toml (default: the demo station)")
    sub = p.add_subparsers(dest="action", required=True)
    add = sub.add_parser("add", help="add a user")
    add.add_argument("name")
    add.add_argument("--role", required=True, choices=ROLES)
    sub.add_parser("list", help="list the users and their roles")
    remove = sub.add_parser("remove", help="remove a user")
    remove.add_argument("name")
    passwd = sub.add_parser("passwd", help="change a user's password")
    passwd.add_argument("name")
    return p


def run_users(argv: list[str]) -> int:
    from app.authority.users import UserError, Users
    from app.scada.words import words
    from app.station.config import read_station, station_file

    ns = _users_parser().parse_args(argv)
    station = read_station(ns.station)[0]
    say = words(station.Language if station is not None else "")
    try:
        users = Users(station_file(ns.station).parent)
        if ns.action == "list":
            for user in users.users.values():
                print(f"{user.name}\t{user.role}")
        elif ns.action == "remove":
            users.remove(ns.name)
            print(say("user removed", user=ns.name))
        elif ns.action == "add":
            users.add(ns.name, ns.role, _password())
            print(say("user added", user=ns.name, role=ns.role))
        else:
            users.passwd(ns.name, _password())
            print(say("password changed", user=ns.name))
    except UserError as e:
        print(f"users: {e}", file=sys.stderr)
        return 1
    return 0


def _password() -> str:
    if not sys.stdin.isatty():
        return sys.stdin.readline().rstrip("\r\n")
    import getpass

    from app.authority.users import UserError

    first = getpass.getpass("password: ")
    if getpass.getpass("again: ") != first:
        raise UserError("passwords differ")
    return first


def _log_level(args: list[str]) -> tuple[str, list[str]]:
    """`--log-level LEVEL` (or `--log-level=LEVEL`) anywhere among the arguments of any command:
    one logging configuration for all of them (app/logs.py)."""
    level, rest, i = "WARNING", [], 0
    while i < len(args):
        arg = args[i]
        if arg == "--log-level" and i + 1 < len(args):
            level, i = args[i + 1].upper(), i + 2
            continue
        if arg.startswith("--log-level="):
            level = arg.split("=", 1)[1].upper()
        else:
            rest.append(arg)
        i += 1
    if level not in LEVELS:
        print(f"--log-level: {level!r} is not one of {', '.join(LEVELS)}", file=sys.stderr)
        raise SystemExit(2)
    return level, rest


def _log_to_station(station: str, level: str) -> None:
    """A running station logs into its own folder (log/station.log)."""
    path = Path(station)
    folder = path.parent if path.suffix == ".toml" else path
    if folder.is_dir():
        logs.to_station_folder(folder, level)


def main(argv: list[str] | None = None) -> int:
    level, args = _log_level(list(sys.argv[1:] if argv is None else argv))
    logs.configure(level)
    if args and args[0] in COMMANDS:
        command, rest = args[0], args[1:]
        if command == "simulate":
            from netplc.simulator import main as simulate

            return simulate(rest)
        if command == "design":
            ns = _design_parser().parse_args(rest)
            return run_designer(ns.target, ns.screenshot)
        if command == "check":
            args = _check_parser().parse_args(rest)
            return run_check(args.station, args.partner or args.partner_option)
        if command == "alarms-report":
            ns = _alarms_report_parser().parse_args(rest)
            return run_alarms_report(ns.archive, ns.day)
        if command == "monitor":
            ns = _monitor_parser().parse_args(rest)
            if ns.target.startswith("opc.tcp://") and not _installed("opcua", "the monitor over OPC UA"):
                return 2
            from app.gui.monitor.window import run_monitor

            return run_monitor(ns.target, ns.program, ns.user, ns.partner)
        if command == "console":
            ns = _console_parser().parse_args(rest)
            if not ns.url.startswith("opc.tcp://"):
                print(f"{ns.url}: not an opc.tcp:// URL", file=sys.stderr)
                return 2
            if not _installed("opcua", "the console"):
                return 2
            from app.gui.console.window import run_console

            return run_console(ns.url, ns.user, ns.partner)
        if command == "archive":
            ns = _archive_parser().parse_args(rest)
            if ns.action == "backup":
                return run_backup(ns.station, ns.dest)
            if ns.action == "restore":
                return run_restore(ns.backup, ns.station)
            if not _installed("postgres", "archive migrate"):
                return 2
            return run_migrate(ns.source, ns.url, ns.station)
        if command == "users":
            return run_users(rest)
        if command == "redundancy":
            return run_redundancy(_redundancy_parser().parse_args(rest).target)
        if command == "opcua":
            if not _installed("opcua", "opcua trust"):
                return 2
            from app.publish.trust import main as opcua

            return opcua(rest)
        archive = _view_parser().parse_args(rest).archive
        if is_url(archive) and not _installed("postgres", "the plant archive"):
            return 2
        return run_viewer(archive)
    ns = _main_parser().parse_args(args)
    if ns.duration is not None and not ns.no_gui:
        _main_parser().error("--duration needs --no-gui")
    _log_to_station(ns.station, level)
    if ns.no_gui:
        return run_headless(ns.station, ns.duration, ns.status_every)
    return run_gui(ns.station, ns.fullscreen)


def _installed(extra: str, what: str) -> bool:
    """Whether the extra `what` needs is installed; if not, says which and how to install it."""
    from app.station.extras import needs

    problem = needs(extra, what)
    if problem:
        print(problem, file=sys.stderr)
    return problem is None


def run_check(station: str, partner: str | None = None) -> int:
    from app.station.check import check_pair, check_station

    report = check_station(station) if partner is None else check_pair(station, partner)
    say = report.words
    for problem in report.problems:
        print(problem)
    for warning in report.warnings:
        print(say("warning", text=warning))
    if report.ok:
        for note in report.notes:
            print(say("ok", text=note))
        return 0
    print(say("problems found", n=len(report.problems)), file=sys.stderr)
    return 1


def run_alarms_report(archive: str, day: str) -> int:
    from registrar.health import alarm_health
    from registrar.query import Archive
    from registrar.schema import parse_table_name

    date = parse_table_name(day)
    if date is None:
        print(f"--day: {day!r} is not a day written DD_MM_YYYY (e.g. 05_03_2026)", file=sys.stderr)
        return 2
    try:
        with Archive(archive) as arch:
            report = alarm_health(arch, date, time.time())
    except (FileNotFoundError, sqlite3.Error) as e:
        print(f"{e}", file=sys.stderr)
        return 2
    print("\n".join(report.lines()))
    return 0


def _open_runtime(station: str):  # -> Runtime | None (typed lazily: the runtime imports the parts)
    from app.station.config import load_station
    from app.station.runtime import Runtime
    from netplc.problems import Problems

    try:
        return Runtime(load_station(station))
    except Problems as e:
        for problem in e.problems:
            print(problem, file=sys.stderr)
        return None


def run_headless(station: str, duration: float | None, every: float) -> int:
    """The station without a window; under systemd (`Type=notify`) it also tells the service
    manager that it is ready, that its scan goes on, and that it stops (app/station/service.py)."""
    from app.station import heap
    from app.station.notify import Notifier
    from app.station.runtime import StartError
    from app.station.service import Service

    runtime = _open_runtime(station)
    if runtime is None:
        return 2
    done = interruptible.Flag()  # raised by the signal handler: no lock (netplc/interruptible.py)
    notifier = Notifier()
    service: Service | None = None

    def on_signal(signum: int, _frame: object) -> None:
        print(f"{signal.Signals(signum).name}: stopping", flush=True)
        done.set()

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        try:
            runtime.start()
        except StartError as e:
            for problem in e.problems:
                print(problem, file=sys.stderr)
            return 2
        print(f"station {runtime.station.name} started: {runtime.station.path}", flush=True)
        heap.settle()  # what the start built lives until the stop: no collection walks it again
        service = Service(runtime, notifier, every)
        service.start()
        started = time.monotonic()
        while not done.is_set():
            left = every if duration is None else min(every, started + duration - time.monotonic())
            if left <= 0 or interruptible.wait(done, left):
                break
            print(runtime.status().line(), flush=True)
    finally:
        if service is not None:
            service.stopping()
        runtime.stop()
        notifier.close()
        for s, handler in previous.items():
            signal.signal(s, handler)
    print(f"station stopped after {runtime.status().line()}", flush=True)
    return 0


def run_gui(station: str, fullscreen: bool = False) -> int:
    from app.gui.main_window import run_workstation

    return run_workstation(station, fullscreen)


def run_viewer(archive: str | None) -> int:
    from app.gui.viewer import run_viewer as viewer

    return viewer(archive)


def run_designer(target: str, screenshot: str | None = None) -> int:
    from app.gui.designer.window import run_designer as designer

    return designer(target, screenshot)


def run_backup(station: str, dest: str) -> int:
    from app.station.backup import BackupError, backup, describe

    try:
        report = backup(station, dest)
    except (BackupError, OSError, sqlite3.Error) as e:
        print(f"archive backup: {e}", file=sys.stderr)
        return 1
    print(f"backup of {station} in {dest}:")
    print("\n".join(f"  {line}" for line in describe(report)))
    return 0


def run_restore(backup: str, station: str) -> int:
    from app.station.backup import BackupError, describe, restore
    from app.station.lock import StationRunning

    try:
        report = restore(backup, station)
    except (BackupError, StationRunning, OSError) as e:
        print(f"archive restore: {e}", file=sys.stderr)
        return 1
    print(f"{backup} restored into {station}:")
    print("\n".join(f"  {line}" for line in describe(report)))
    return 0


def run_migrate(source: str, url: str, station: str | None) -> int:
    """Copy a SQLite archive into the plant archive, with a progress bar on stderr, under the name
    its station's forwarder uses, so the same record never lands twice (the key is station, day, id)."""
    from app.station.config import archive_owner, read_station
    from registrar.plant.forward import Forwarder
    from registrar.plant.url import is_url, url_problem
    from registrar.query import Archive
    from registrar.reading import ArchiveError

    problem = url_problem(url) if is_url(url) else "not a postgresql:// URL"
    if problem:
        print(f"{url}: {problem}", file=sys.stderr)
        return 2
    path = Path(source)
    a_station = path.is_dir() or path.suffix == ".toml"  # its Archive, by its name
    if a_station:
        owner, problems = read_station(path)
    else:  # an archive file: the station whose Archive it is, unless named
        owner, problems = archive_owner(path) if station is None else (None, [])
    if problems and (a_station or owner is not None):
        print("\n".join(problems), file=sys.stderr)
        print("the station file has problems (see `main.py check`): fix it, or give the archive file "
              "and --station NAME", file=sys.stderr)
        return 2
    if a_station and owner is not None:
        path = owner.Archive
    if not path.is_file():
        print(f"{path}: no such archive", file=sys.stderr)
        return 2
    name, why = station, "--station"
    if name is None and owner is not None:
        name, why = owner.name, f"the name in {owner.path}"
    if name is None:
        try:
            with Archive(path) as archive:
                name, why = archive.meta().get("station"), "the name the archive keeps"
        except sqlite3.Error as e:
            print(f"{path}: {e}", file=sys.stderr)
            return 1
    if not name:
        print("\n".join([*problems, f"{path}: cannot tell whose archive it is: no station.toml in its "
                          "folder or above names it as its Archive, and it keeps no station name; give "
                          "--station NAME (the `name` in the station's station.toml)"]), file=sys.stderr)
        return 2

    def progress(sent: int, total: int) -> None:
        done = min(1.0, sent / total) if total else 1.0
        bar = "#" * round(30 * done)
        print(f"\r[{bar:<30}] {sent:,} / {total:,} records", end="", file=sys.stderr, flush=True)

    # one of a hot-standby pair: as its letter, so its records keep the keys its forwarder gives them
    letter = owner.redundancy.letter if owner is not None and owner.redundancy is not None else ""
    try:
        n = Forwarder(path, url, name, letter=letter).forward_all(progress)
    except (ArchiveError, sqlite3.Error) as e:
        print(f"\n{path} -> {url}: {e}", file=sys.stderr)
        return 1
    print(("\n" if n else "") + f"{n:,} records copied from {path} to {url} as station {name!r} "
          f"({why}; records already there are not copied again)")
    return 0
