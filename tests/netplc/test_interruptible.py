"""A signal delivered to another thread than the main one still reaches Python's handler while
the main thread waits (the simulator once ignored Ctrl-C for good that way)."""

from __future__ import annotations

import signal
import threading

from netplc import interruptible


def test_a_signal_to_another_thread_ends_the_main_threads_wait() -> None:
    done = interruptible.Flag()
    previous = signal.signal(signal.SIGUSR1, lambda _signum, _frame: done.set())  # runs on the main thread
    try:
        # once the main thread waits, the signal goes to the sender's thread, not to the waiting one
        sender = threading.Timer(0.1, lambda: signal.pthread_kill(threading.get_ident(), signal.SIGUSR1))
        sender.start()
        assert interruptible.wait(done)  # for ever unless the handler runs: a blocking wait hangs
        sender.join()
    finally:
        signal.signal(signal.SIGUSR1, previous)


def test_a_wait_with_a_time_ends_unset_when_nothing_comes() -> None:
    assert not interruptible.wait(interruptible.Flag(), 0.05)
