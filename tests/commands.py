"""Commands (`main.py ...`, `python -m netplc ...`) run in this process, for the tests about what a
command prints and the status it returns rather than about its process: a subprocess spends most
of its CPU starting an interpreter and importing the project, which a worker has done once.
`main.py` and `netplc/__main__.py` are `sys.exit(main())`, so what `main` returns is the exit
status; each file that runs commands here keeps one real subprocess that proves it."""

from __future__ import annotations

import subprocess
from collections.abc import Callable, Sequence

import pytest


def run_in_process(main: Callable[[list[str]], int], args: Sequence[object],
                   capsys: pytest.CaptureFixture[str]) -> subprocess.CompletedProcess[str]:
    """`main(args)` as a finished process: its status, and what it wrote to stdout and stderr."""
    capsys.readouterr()
    argv = [str(a) for a in args]
    try:
        code = main(argv)
    except SystemExit as e:  # argparse refusing an option, as the process would exit
        code = e.code if isinstance(e.code, int) else 1
    out, err = capsys.readouterr()
    return subprocess.CompletedProcess(argv, code, out, err)
