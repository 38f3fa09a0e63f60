"""Waiting on the main thread without deafening it to Ctrl-C and SIGTERM.

A signal may be delivered to any thread of the process; Python runs its handler (the
KeyboardInterrupt of Ctrl-C, the station's SIGTERM handler) on the main thread, at its next
bytecode. A main thread blocked in a lock without a timeout (`Event().wait()`) never gets there
when the signal went to a scan or network thread: the simulator then ignored Ctrl-C for good (seen
under load in the suite). Waiting in short slices bounds the delay to one slice.
"""

from __future__ import annotations

import threading
import time

SLICE = 0.2  # s: the longest a signal waits for the main thread


def wait(event: threading.Event, seconds: float | None = None) -> bool:
    """`event.wait(seconds)` (None: for ever) in slices of SLICE; True once the event is set."""
    end = None if seconds is None else time.monotonic() + seconds
    while not event.is_set():
        left = SLICE if end is None else min(SLICE, end - time.monotonic())
        if left <= 0:
            return False
        event.wait(left)
    return True
