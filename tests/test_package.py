"""The package as a user installs it: the wheel built from the source, installed with pip into a
fresh venv, gives the command `netplc-station`, which finds the demo station and the compiled
translations inside the package, runs the demo headless until SIGTERM and checks it meanwhile.

One test, so that the wheel is built and installed once however the suite is spread over
workers. The venv sees the test venv's site-packages through a .pth file, so pip resolves the
wheel's dependencies against what is installed there and installs our wheel alone (no index, no
download of PySide6 and the rest); pip leaves the test venv untouched (what it finds there is
"outside environment"). The venv's own interpreter runs that pip (found through the same .pth),
as `pip --python` would after starting a first pip only to start it there. The wheel is built by
the PEP 517 backend pyproject.toml names, called as pip calls it, in this venv (with the test
extra's setuptools) rather than in an isolated build environment pip would first install: the
same wheel, in a quarter of the time.

What is not what the test proves is left out (about 1.5 s of CPU): the machine's pip configuration
(its indexes and constraints), pip's check of every other installed package's requirements, and
pip's compiling of every module of the wheel, most of which a headless station never imports (the
installed command compiles what it imports on its first run and writes it to the venv, as it
would for a user). The console script runs the station; the venv's python, in one process, says
where the code finds the demo and the translations, the version the wheel's metadata holds (what
`--version` prints is checked in this process) and checks the demo as `netplc-station check` does
(`app.cli.main`, what the console script calls).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import tomllib
import venv as venvs
import zipfile
from pathlib import Path

import pytest

from app import __version__
from app.cli import main as cli
from tests.app.conftest import DEMO_NAME, stop_once_up
from tests.commands import run_in_process

REPO = Path(__file__).resolve().parents[1]
SOURCES = ("pyproject.toml", "README.md", "app", "netplc", "registrar", "hmi_forms")
DERIVED = shutil.ignore_patterns("__pycache__", "*.pyc", "archive", "log", "station.lock", "build",
                                 "*.egg-info")


def pip(venv: Path, *args: str, timeout: float = 300) -> None:
    """pip of the venv, without the machine's configuration (PIP_CONFIG_FILE=/dev/null: no index,
    find-links or constraints of this machine's pip.conf)."""
    r = subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "--disable-pip-version-check", *args],
                       capture_output=True, text=True, timeout=timeout,
                       env={**os.environ, "PIP_CONFIG_FILE": os.devnull})
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


def fresh_venv(tmp: Path) -> tuple[Path, Path]:
    """A venv as `python -m venv --without-pip` makes it (made in this process), and its
    site-packages."""
    venv = tmp / "venv"
    venvs.EnvBuilder(symlinks=os.name != "nt", with_pip=False).create(venv)
    site = Path(sysconfig.get_path("purelib", vars={"base": str(venv), "platbase": str(venv)}))
    assert site.is_dir(), site
    (site / "test-venv.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return venv, site


def run(venv: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(args, cwd=venv, env=installed_env(venv), capture_output=True, text=True,
                          timeout=120)


def installed_env(venv: Path) -> dict[str, str]:
    """No PYTHONPATH: the package must come from the venv, not from this checkout. Bytecode is
    written (where the environment forbids it, the installed package, not compiled by pip, would
    be compiled again by each run)."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONDONTWRITEBYTECODE")}
    env["PYTHONFAULTHANDLER"] = "1"  # a station that hangs shows where (tests/app/conftest.py stop_once_up)
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    return env


def test_the_wheel_installs_netplc_station_with_the_demo_and_the_translations(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    wheel = build_wheel(tmp_path)
    names = set(zipfile.ZipFile(wheel).namelist())
    demo_files = ("station.toml", "users.json", "netplc.stl", "forms/02_analog.hmi", "forms/images/tank.png")
    assert {*(f"app/station/demo/{f}" for f in demo_files), "app/gui/i18n/console_ru.qm"} <= names
    assert not [n for n in names if "/archive/" in n or "/log/" in n or n.endswith("station.lock")]

    venv, site = fresh_venv(tmp_path)
    pip(venv, "install", "-q", "--no-index", "--no-compile", "--no-warn-conflicts", str(wheel))  # its
    command = str(venv / "bin" / "netplc-station")  # dependencies resolved against what is installed

    station = subprocess.Popen([command, "--no-gui", "--status-every", "0.5"],  # the demo: no folder given
                               cwd=venv, env=installed_env(venv), stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        assert station.stdout is not None
        first = station.stdout.readline()  # started: what it imports compiled, for the next to read
        r = run(venv, str(venv / "bin" / "python"), "-c",  # while the demo runs
                "import sys\nfrom importlib.metadata import version\nfrom app.cli import main\n"
                "from app.station.config import DEMO_STATION\nfrom app.gui.i18n import compiled\n"
                "print(version('netplc-station')); print(DEMO_STATION); print(compiled('ru'), flush=True)\n"
                "sys.exit(main(['check', str(DEMO_STATION)]))")
    finally:
        out, err = stop_once_up(station)
    out = first + out
    installed, demo, qm = (Path(line) for line in r.stdout.split("\n")[:3])
    assert str(installed) == __version__ and demo == site / "app" / "station" / "demo", r.stdout + r.stderr
    assert qm == site / "app" / "gui" / "i18n" / "console_ru.qm"
    assert r.returncode == 0, r.stdout + r.stderr  # the demo checks clean
    assert f"норма: станция {demo / 'station.toml'}" in r.stdout  # the demo's Language is ru
    assert station.returncode == 0, err
    lines = out.splitlines()
    assert lines[0] == f"station {DEMO_NAME} started: {demo / 'station.toml'}", out
    assert "nodes 1/1 up" in out and "SIGTERM: stopping" in out
    assert lines[-1].startswith("station stopped after")
    assert (demo / "archive" / "journal.sqlite").is_file()  # the installed demo runs where it is

    assert run_in_process(cli, ["--version"], capsys).stdout == f"netplc-station {__version__}\n"
