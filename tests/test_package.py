"""The package as a user installs it: the wheel built from the source, installed with pip into a
fresh venv, gives the command `netplc-station`, which finds the demo station and the compiled
translations inside the package, checks the demo and runs it headless until SIGTERM.

One test, so that the wheel is built and installed once however the suite is spread over
workers (about 10 s, most of it pip). The venv sees the test venv's site-packages through a .pth
file, so pip resolves the wheel's dependencies against what is installed there and installs our
wheel alone (no download of PySide6 and the rest); pip leaves the test venv untouched (what it
finds there is "outside environment"). The venv's own interpreter runs that pip (found through the
same .pth), as `pip --python` would after starting a first pip only to start it there. The wheel
is built by the PEP 517 backend pyproject.toml names, called as pip calls it, in this venv (with
the test extra's setuptools) rather than in an isolated build environment pip would first install:
the same wheel, in a quarter of the time.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import tomllib
import zipfile
from pathlib import Path

from app import __version__
from tests.app.conftest import DEMO_NAME, stop_once_up

REPO = Path(__file__).resolve().parents[1]
SOURCES = ("pyproject.toml", "README.md", "app", "netplc", "registrar", "hmi_forms")
DERIVED = shutil.ignore_patterns("__pycache__", "*.pyc", "archive", "log", "station.lock", "build",
                                 "*.egg-info")


def pip(venv: Path, *args: str, timeout: float = 300) -> None:
    r = subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "--disable-pip-version-check", *args],
                       capture_output=True, text=True, timeout=timeout)
    assert r.returncode == 0, r.stdout + r.stderr


def build_wheel(tmp: Path) -> Path:
    """The wheel of a copy of the source (a build writes build/ and *.egg-info beside it), with the
    console's .qm compiled first as `make dist` does."""
    from app.gui.i18n import compiled

    assert compiled("ru") is not None
    src = tmp / "src"
    src.mkdir()
    for name in SOURCES:
        path = REPO / name
        if path.is_dir():
            shutil.copytree(path, src / name, ignore=DERIVED)
        else:
            shutil.copy2(path, src / name)
    backend = tomllib.loads((src / "pyproject.toml").read_text())["build-system"]["build-backend"]
    code = f"import importlib; importlib.import_module({backend!r}).build_wheel({str(tmp / 'dist')!r})"
    r = subprocess.run([sys.executable, "-c", code], cwd=src, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    (wheel,) = (tmp / "dist").glob("netplc_station-*.whl")
    return wheel


def fresh_venv(tmp: Path) -> Path:
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    python = venv / "bin" / "python"
    site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          capture_output=True, text=True, check=True, timeout=60).stdout.strip()
    (Path(site) / "test-venv.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return venv


def run(venv: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(args, cwd=venv, env=installed_env(venv), capture_output=True, text=True,
                          timeout=120)


def installed_env(venv: Path) -> dict[str, str]:
    """No PYTHONPATH: the package must come from the venv, not from this checkout."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONFAULTHANDLER"] = "1"  # a station that hangs shows where (tests/app/conftest.py stop_once_up)
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    return env


def test_the_wheel_installs_netplc_station_with_the_demo_and_the_translations(tmp_path: Path) -> None:
    wheel = build_wheel(tmp_path)
    names = set(zipfile.ZipFile(wheel).namelist())
    demo_files = ("station.toml", "users.json", "netplc.stl", "forms/02_analog.hmi", "forms/images/tank.png")
    assert {*(f"app/station/demo/{f}" for f in demo_files), "app/gui/i18n/console_ru.qm"} <= names
    assert not [n for n in names if "/archive/" in n or "/log/" in n or n.endswith("station.lock")]

    venv = fresh_venv(tmp_path)
    pip(venv, "install", "-q", str(wheel))  # its dependencies resolved
    command = str(venv / "bin" / "netplc-station")

    r = run(venv, command, "--version")
    assert (r.returncode, r.stdout) == (0, f"netplc-station {__version__}\n"), r.stderr
    r = run(venv, str(venv / "bin" / "python"), "-c",
            "from app.station.config import DEMO_STATION; from app.gui.i18n import compiled\n"
            "print(DEMO_STATION); print(compiled('ru'))")
    demo, qm = (Path(line) for line in r.stdout.split())
    assert demo.is_relative_to(venv) and (demo / "station.toml").is_file(), r.stderr
    assert qm.is_relative_to(venv) and qm.name == "console_ru.qm"

    station = subprocess.Popen([command, "--no-gui", "--status-every", "0.5"],  # the demo: no folder given
                               cwd=venv, env=installed_env(venv), stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        r = run(venv, command, "check", str(demo))  # while the demo starts
    finally:
        out, err = stop_once_up(station)
    assert r.returncode == 0, r.stdout + r.stderr
    assert f"норма: станция {demo / 'station.toml'}" in r.stdout  # the demo's Language is ru
    assert station.returncode == 0, err
    lines = out.splitlines()
    assert lines[0].startswith(f"station {DEMO_NAME} started"), out
    assert "nodes 1/1 up" in out and "SIGTERM: stopping" in out
    assert lines[-1].startswith("station stopped after")
    assert (demo / "archive" / "journal.sqlite").is_file()  # the installed demo runs where it is
