"""A big program's first compile, done by a child process so that the first scan need not wait.

Generating and compiling the 8 K-word program takes 200-400 ms, as long as a whole start's imports,
and `compile()` holds the GIL throughout: in the station's process it would delay the first scan,
or stall the scans from a thread. When a start finds no compiled code (archive/compiled/) for a
program of BEHIND_MIN instructions or more, the engine scans with the reference interpreter (the same
memory, timers, counters and functions: the equivalence tests hold the two backends to identical
results) while a child Python generates and compiles the code from the instructions; the engine
takes the code between two scans (`compile_program_behind`). The child starts after the first
scan and runs at a lower priority (NICE): the start and the scans go first on a busy machine. A
child that fails or hangs is logged and the code is compiled in the station's process instead, as
before. Programs below BEHIND_MIN compile in place: a child would cost more than their compile.

The child is this module run as `python -m netplc.compile_behind`: the program's instructions and
in-line functions come on its stdin and the code object goes back on its stdout, both marshalled.
"""

from __future__ import annotations

import logging
import marshal
import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from types import CodeType

from netplc.backend import Backend, ScanHost
from netplc.codecache import CodeCache
from netplc.compiler import backend_of, code_rows, compile_code, compile_program, fon_code, program_key
from netplc.program import Instr, Program

logger = logging.getLogger(__name__)
BEHIND_MIN = 2000  # instructions: about 70 ms of compile, twice what a child's start costs
TIMEOUT = 120.0  # seconds a child may take before it is killed and the station compiles itself
PYTHON = sys.executable  # the child's interpreter: the station's own
NICE = 10  # the child's niceness added: on a busy machine it takes the CPU the station leaves
AFTER_S = 5.0  # the longest the child waits for the first scan (an engine that never scans, a standby)


def compile_program_behind(program: Program, engine: ScanHost, cache: CodeCache,
                           ready: Callable[[Backend], None], after: threading.Event) -> Backend | None:
    """`compile_program` with `cache` (netplc/compiler.py), except that a program of BEHIND_MIN
    instructions or more that the cache lacks is compiled by a child process, started once `after`
    is set (the engine's first scan) or AFTER_S have passed: None is returned at once (the caller
    scans with the interpreter) and `ready(backend)` is called from a thread when the code is there
    and kept in the cache."""
    if len(program.instrs) < BEHIND_MIN:
        return compile_program(program, engine, cache)
    inline, steps = fon_code(engine)
    key = program_key(program, inline)
    code = cache.load(key)
    if code is not None:
        return backend_of(code, program, engine, steps)

    def done(code: CodeType | None) -> None:
        try:
            if code is None:  # the child failed (logged): compiled here, as without a child
                code = compile_code(program, inline)
            cache.store(key, code)
            ready(backend_of(code, program, engine, steps))
        except Exception:
            logger.exception("%s not compiled: the interpreter goes on running its scans", program.source)

    start(program, inline, done, after)
    return None


def start(program: Program, inline: dict[int, list[str]], done: Callable[[CodeType | None], None],
          after: threading.Event) -> None:
    """Compile `program` in a child process once `after` is set (or AFTER_S have passed); `done(code)`
    from a thread when it is there, `done(None)` (after logging why) when the child failed. The
    thread is not a daemon: a station that stops meanwhile still gets its code into the cache for
    the next start."""

    def compile_after() -> None:
        after.wait(AFTER_S)
        done(child_code(marshal.dumps((program.source, code_rows(program), inline)), program.source))

    threading.Thread(target=compile_after, name="netplc-compile", daemon=False).start()


def child_code(payload: bytes, source: str) -> CodeType | None:
    """The code object the child compiled from `payload`, or None (logged)."""
    root = str(Path(__file__).resolve().parent.parent)  # this very netplc, installed or not
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p)}
    flags = ["-" + "O" * sys.flags.optimize] if sys.flags.optimize else []
    t0 = time.monotonic()
    try:
        proc = subprocess.run([PYTHON, *flags, "-m", __name__], input=payload, capture_output=True,
                              env=env, timeout=TIMEOUT, check=False)
    except (OSError, subprocess.SubprocessError):
        logger.exception("the child process compiling %s did not run; compiling in this process", source)
        return None
    if proc.returncode != 0:
        tail = proc.stderr.decode(errors="replace").strip().splitlines()[-3:]
        logger.error("the child process compiling %s failed (exit code %s): %s; compiling in this process",
                     source, proc.returncode, " / ".join(tail) or "no message")
        return None
    try:
        code = marshal.loads(proc.stdout)
    except (ValueError, EOFError, TypeError):
        logger.exception("the child process compiling %s answered no code; compiling in this process", source)
        return None
    if not isinstance(code, CodeType):
        logger.error("the child process compiling %s answered a %s, not code; compiling in this process",
                     source, type(code).__name__)
        return None
    logger.info("%s compiled by a child process in %.0f ms; the interpreter ran the scans until now",
                source, (time.monotonic() - t0) * 1000.0)
    return code


def main() -> None:
    os.nice(NICE)  # the station's own threads first: they start, scan and answer meanwhile
    source, rows, inline = marshal.loads(sys.stdin.buffer.read())
    program = Program([Instr(*row) for row in rows], source=source)
    sys.stdout.buffer.write(marshal.dumps(compile_code(program, inline)))


if __name__ == "__main__":
    main()
