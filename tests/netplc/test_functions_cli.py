"""The function tutorial of the manual is true: each `$ python -m netplc run ...`
line in its console blocks is run from the repository root, and its output must be the one shown
(a command shown twice runs once). The command runs in this process (`netplc.cli.main`, what
`python -m netplc` calls; tests/netplc/test_cli.py runs the module as a process too)."""

from __future__ import annotations

import shlex
from pathlib import Path

import pytest

from netplc.cli import main
from tests.commands import run_in_process

ROOT = Path(__file__).resolve().parents[2]
PROMPT = "$ python -m netplc run "
TUTORIALS = ("docs/engineer/programs.md",)


def tutorial_commands(name: str) -> list[tuple[str, list[str]]]:
    """(command line, expected output lines) for every command of the `## Function tutorial` section."""
    text = (ROOT / name).read_text(encoding="utf-8")
    section = text.split("\n## Function tutorial\n", 1)[1].split("\n## ", 1)[0]
    commands: list[tuple[str, list[str]]] = []
    in_console = False
    for line in section.splitlines():
        if line.startswith("```"):
            in_console = line == "```console"
        elif in_console and line.startswith(PROMPT):
            commands.append((line[2:], []))
        elif in_console and commands:
            commands[-1][1].append(line)
    return commands


BY_FILE = {name: tutorial_commands(name) for name in TUTORIALS}
COMMANDS = list({(c, tuple(out)): (c, out) for commands in BY_FILE.values() for c, out in commands}.values())


@pytest.mark.parametrize("name", TUTORIALS)
def test_the_tutorial_covers_the_required_examples(name: str) -> None:
    programs = [shlex.split(cmd)[4] for cmd, _ in BY_FILE[name]]
    for example, times in (("mov", 1), ("bcdw", 1), ("addbcd", 2), ("cmp", 2)):
        assert programs.count(f"tests/vectors/tutorial/{example}.stl") == times, name


@pytest.mark.parametrize(("command", "expected"), COMMANDS, ids=[c for c, _ in COMMANDS])
def test_tutorial_command_prints_what_the_tutorial_shows(command: str, expected: list[str],
                                                         capsys: pytest.CaptureFixture[str],
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    python, dash_m, module, *args = shlex.split(command)
    assert (python, dash_m, module) == ("python", "-m", "netplc")
    monkeypatch.chdir(ROOT)
    done = run_in_process(main, args, capsys)
    assert (done.stdout + done.stderr).splitlines() == expected
    assert done.returncode == (2 if "bad.stl" in command else 0)
