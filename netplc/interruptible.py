"""Waiting on the main thread for a signal, without deafening it and without a lock.

A signal may be delivered to any thread of the process; Python runs its handler (the
KeyboardInterrupt of Ctrl-C, a station's SIGTERM handler) on the main thread, at its next
bytecode. A main thread blocked in a lock without a timeout (`Event().wait()`) never gets there
when the signal went to a scan or network thread: the simulator then ignored Ctrl-C for good.
And a handler must take no lock the main thread may hold when the handler interrupts it:
`Event.set()` in a handler deadlocked the headless station when the signal came while the main
thread was inside that Event's `wait()` (seen in the suite). So the handler raises a `Flag` (a
plain attribute) and the main thread sleeps in short slices, looking at it between them.
"""

from __future__ import annotations

import time

SLICE = 0.1  # s: the longest a signal waits for the main thread


class Flag:
    """Raised by a signal handler, read by the main thread: no lock on either side."""

    def __init__(self) -> None:
        self.raised = False

    def set(self) -> None:
        self.raised = True

    def is_set(self) -> bool:
        return self.raised


def wait(flag: Flag, seconds: float | None = None) -> bool:
    """Until `flag` is raised (True) or `seconds` passed (None: for ever; False)."""
    end = None if seconds is None else time.monotonic() + seconds
    while not flag.raised:
        left = SLICE if end is None else min(SLICE, end - time.monotonic())
        if left <= 0:
            return False
        time.sleep(left)
    return True
