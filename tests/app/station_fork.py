"""Headless stations started as processes of their own, forked from one that has imported them.

`python main.py --no-gui STATION` spends most of its start importing (a second of CPU); a test that
starts a station twenty times spends it twenty times. Here a child process (`Forks`) imports
`app.cli`, the runtime and what a station's start imports lazily, once, and then forks on request;
each fork runs `app.cli.main` with the arguments given, exactly as `main.py` does, and ends with its
exit code. The test signals the fork by its PID like any process and asks the forking process, its
parent, for its exit code (`Forked`, a small Popen).

    python -m tests.app.station_fork    (requests on stdin, one JSON array a line)
"""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


class Forks:
    """The forking process: start it, `start()` stations, `close()` it."""

    def __init__(self, stderr: Path) -> None:
        with open(stderr, "ab") as err:
            self.proc = subprocess.Popen([sys.executable, "-m", "tests.app.station_fork"], cwd=REPO,
                                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=err, text=True)

    def ask(self, *request: object) -> object:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(json.dumps(request) + "\n")
        self.proc.stdin.flush()
        answer = self.proc.stdout.readline()
        if not answer:
            raise RuntimeError(f"the forking process ended (exit code {self.proc.wait(10)})")
        return json.loads(answer)

    def start(self, args: list[str], stderr: Path, stdout: Path | None = None,
              env: dict[str, str] | None = None, stdin: Path | None = None) -> Forked:
        """`python main.py ARGS` with its stderr appended to `stderr`, its stdout to `stdout` (or
        dropped), `env` added to its environment, and its stdin read from `stdin` (or empty)."""
        pid = self.ask("start", args, str(stderr), str(stdout or os.devnull), env or {},
                       str(stdin or os.devnull))
        assert isinstance(pid, int)
        return Forked(self, pid, stderr, stdout)

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        assert self.proc.wait(10) == 0


class Forked:
    """One forked station, like a `subprocess.Popen` of it."""

    def __init__(self, forks: Forks, pid: int, stderr: Path, stdout: Path | None) -> None:
        self.forks, self.pid = forks, pid
        self.stderr, self.stdout = stderr, stdout
        self.returncode: int | None = None

    def output(self) -> str:
        """What it printed so far (its prints are flushed line by line)."""
        assert self.stdout is not None
        return self.stdout.read_text(encoding="utf-8") if self.stdout.exists() else ""

    def errors(self) -> str:
        return self.stderr.read_text(encoding="utf-8", errors="replace") if self.stderr.exists() else ""

    def until(self, said: Callable[[str], bool], timeout: float = 30.0) -> str:
        """Its output once `said(output)` holds, polled every 20 ms; AssertionError if it ends or
        `timeout` s pass first."""
        deadline = time.monotonic() + timeout
        while not said(out := self.output()):
            if self.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"station {self.pid} (exit code {self.returncode}) said:\n"
                                     f"{out}{self.errors()}")
            time.sleep(0.02)
        return out

    def send_signal(self, sig: int) -> None:
        if self.returncode is None:
            os.kill(self.pid, sig)

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)

    def poll(self) -> int | None:
        return self.wait(0) if self.returncode is None else self.returncode

    def wait(self, timeout: float) -> int | None:
        """The exit code (minus the signal that ended it), or None if it runs on after `timeout`
        (`poll()` with 0)."""
        if self.returncode is None:
            code = self.forks.ask("wait", self.pid, timeout)
            if code is None and timeout:
                raise subprocess.TimeoutExpired(f"station {self.pid}", timeout)
            self.returncode = code  # type: ignore[assignment]
        return self.returncode


def _fork(args: list[str], stderr: str, stdout: str, env: dict[str, str], stdin: str) -> int:
    from app.cli import main

    sys.stdout.flush()
    pid = os.fork()
    if pid:
        return pid
    os.environ.update(env)
    given = os.open(stdin, os.O_RDONLY)
    os.dup2(given, 0)
    os.close(given)
    sys.stdin = open(0, encoding="utf-8", closefd=False)  # noqa: SIM115  (not the requests' buffer)
    for fd, path in ((1, stdout), (2, stderr)):
        out = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        os.dup2(out, fd)
        os.close(out)
    sys.exit(main(args))  # and the interpreter ends as main.py's does


def _wait(pid: int, timeout: float) -> int | None:
    """The exit code of the fork `pid` once it ended, or None if it still runs after `timeout` s."""
    fd = os.pidfd_open(pid)
    try:
        select.select([fd], [], [], timeout)
        done, status = os.waitpid(pid, os.WNOHANG)
    finally:
        os.close(fd)
    return os.waitstatus_to_exitcode(status) if done else None


def serve() -> None:
    # what every fork would import first: the command line, the runtime, and what a start imports
    # lazily (numpy for the quality of the tags, netplc/lazy.py: 0.6 s of a fork's start otherwise;
    # the service manager's notifier) and what the first bytes through a socket need (idna)
    import encodings.idna  # noqa: F401

    import numpy  # noqa: F401

    import app.cli
    import app.station.runtime
    import app.station.service  # noqa: F401
    import hmi_forms.behaviour  # noqa: F401  (the forms of a station that has them)

    for line in sys.stdin:
        request = json.loads(line)
        if request[0] == "start":
            answer: object = _fork(*request[1:])
        else:
            answer = _wait(request[1], request[2])
        print(json.dumps(answer), flush=True)


if __name__ == "__main__":
    serve()
